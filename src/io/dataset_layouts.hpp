#pragma once
// Internal to io/: the per-layout readers behind open_dataset() and their shared helpers.
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "semap/io/dataset.hpp"

namespace semap::io_detail {

/// Ground-truth poses are matched to frame timestamps within this gap (TUM convention).
constexpr double kMaxTimeDifference = 0.02;

/// One line of a TUM-style list: "timestamp field...".
struct ListEntry {
  double timestamp = 0.0;
  std::vector<std::string> fields;
  size_t line = 0;
};
/// Reads a list file; errors name the file and line (malformed, non-finite, duplicate or
/// decreasing timestamps, fewer than `min_fields` fields after the timestamp).
std::vector<ListEntry> read_list(const std::filesystem::path& path, size_t min_fields = 1);
/// root / relative (absolute paths stay); throws naming the list and line when the file is absent.
std::filesystem::path listed_file(const std::filesystem::path& list, const ListEntry& entry, size_t field);

/// Pose at time t: interpolated between the bracketing poses when both are within max_dt,
/// else the nearest within max_dt, else nullopt.
std::optional<Pose> pose_at(const Trajectory& trajectory, double t, double max_dt = kMaxTimeDifference);
/// 4x4 (or 3x4) row-major matrix text -> rigid pose. nullopt for non-finite values (unknown pose);
/// throws naming the file when malformed or not a rotation.
std::optional<Pose> read_matrix_pose(const std::filesystem::path& path);
/// Rigid pose from 12 or 16 row-major numbers; throws Error(where) when not a rotation.
Pose pose_from_rows(const std::vector<double>& m, const std::string& where);

/// dataset.yaml: optional format and camera overrides.
struct DatasetYaml {
  std::filesystem::path file;
  std::string format;  ///< empty = detect from the layout
  YAML::Node camera;   ///< may be null
};
DatasetYaml read_dataset_yaml(const std::filesystem::path& file);
/// Applies the yaml camera keys (the rest keep the layout's defaults) and validates.
void apply_yaml_camera(const DatasetYaml* yaml, CameraModel& camera);

/// A reader of any layout once its records are known.
class LayoutDataset : public DatasetReader {
 public:
  LayoutDataset(std::string format, std::filesystem::path root, CameraModel camera, std::vector<FrameRecord> records)
      : format_(std::move(format)) {
    root_ = std::move(root);
    set_camera(camera, root_.string());  // the readers name their camera file first
    records_ = std::move(records);
  }
  std::string format() const override { return format_; }

 private:
  std::string format_;
};

std::unique_ptr<DatasetReader> open_tum(const std::filesystem::path& root, const DatasetYaml* yaml);
std::unique_ptr<DatasetReader> open_7scenes(const std::filesystem::path& root, const DatasetYaml* yaml);
std::unique_ptr<DatasetReader> open_ycb(const std::filesystem::path& root, const DatasetYaml* yaml);
std::unique_ptr<DatasetReader> open_synthetic(const std::filesystem::path& root, const DatasetYaml* yaml,
                                              const DatasetOptions& options);
/// ScanNet exported layout (color/N.jpg, depth/N.png, pose/N.txt, intrinsic/*.txt).
std::unique_ptr<DatasetReader> open_scannet(const std::filesystem::path& root, const DatasetYaml* yaml);
/// ScanNet .sens recording (one file: calibration, then per frame pose, JPEG colour, zlib depth).
std::unique_ptr<DatasetReader> open_scannet_sens(const std::filesystem::path& file);
/// ROS1 bag (rosbag_dataset.cpp): colour and depth image topics associated by timestamp.
std::unique_ptr<DatasetReader> open_rosbag(const std::filesystem::path& bag, const DatasetOptions& options);
/// rosbag2 (issue 40, rosbag2_bag.hpp): a bag folder or one .db3 / .mcap file, read like a ROS1 bag.
std::unique_ptr<DatasetReader> open_rosbag2(const std::filesystem::path& bag, const DatasetOptions& options);

/// rgb <-> depth records from two lists associated by timestamp (max 0.02 s, one-to-one);
/// frame timestamp = rgb timestamp; unmatched rgb frames are dropped.
std::vector<FrameRecord> associate_lists(const std::filesystem::path& rgb_list,
                                         const std::filesystem::path& depth_list);
/// Fills gt_T_world_camera of each record from a trajectory (pose_at), then
/// use_local_origin_if_far(records, source).
void attach_ground_truth(std::vector<FrameRecord>& records, const Trajectory& trajectory,
                         const std::string& source = "ground truth");
/// Ground-truth positions farther than this from the origin are taken as georeferenced.
constexpr double kMaxGroundTruthDistanceM = 1000.0;
/// Georeferenced ground truth (translations of 1e5 m: float maps lose all precision there):
/// when any pose is farther than kMaxGroundTruthDistanceM from the origin, the first pose's
/// translation is subtracted from every pose (a local origin), with one warning naming `source`.
void use_local_origin_if_far(std::vector<FrameRecord>& records, const std::string& source);

}  // namespace semap::io_detail
