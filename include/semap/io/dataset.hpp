#pragma once
// Dataset readers: frames stream from disk one at a time (a 10 000-frame sequence is never
// loaded at once). open_dataset() picks the reader from the folder layout or a dataset.yaml.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"
#include "semap/core/labels.hpp"

namespace semap {

class LensUndistortion;  // core/lens_undistortion.hpp (internal)

/// One entry of a sequence: which files make frame i (decoded lazily).
struct FrameRecord {
  double timestamp = 0.0;
  std::filesystem::path rgb, depth;
  std::filesystem::path labels, instances;  ///< optional ground-truth label images
  std::optional<Pose> gt_T_world_camera;
};

class DatasetReader {
 public:
  virtual ~DatasetReader() = default;
  /// "tum", "7scenes", "ycb", "synthetic", "scannet", "scannet-sens", "rosbag".
  virtual std::string format() const = 0;
  /// The dataset folder, or the file (.bag, .sens) for single-file formats.
  const std::filesystem::path& root() const { return root_; }
  /// The camera of the delivered images: a lens with distortion (TUM fr1/fr2 presets,
  /// dataset.yaml `distortion`) is undistorted on load, and this camera is then its pinhole model.
  const CameraModel& camera() const { return camera_; }
  size_t size() const { return records_.size(); }
  const std::vector<FrameRecord>& records() const { return records_; }
  /// Decodes frame i (throws semap::Error naming the file when it is unreadable/inconsistent),
  /// undistorted. Thread safety: const, may run concurrently with other loads.
  Frame load(size_t i) const;
  /// Decodes only the depth image of frame i (CV_32FC1 metres), validated and undistorted as load() does.
  cv::Mat load_depth(size_t i) const;
  /// Ground-truth trajectory of the sequence (per frame, where known).
  Trajectory ground_truth() const;
  bool has_ground_truth() const;
  /// True when per-frame label/instance ground truth exists.
  bool has_label_ground_truth() const;

 protected:
  /// The layout's own decoding of frame i / its depth, as stored (before undistortion).
  virtual Frame decode(size_t i) const;
  virtual cv::Mat decode_depth(size_t i) const;
  /// Sets the camera of the stored images; with lens distortion, load() undistorts and
  /// camera() reports the pinhole model. The one camera check every reader goes through
  /// (issue 44): validate_camera (CameraLimits: finite, plausible intrinsics, principal point
  /// inside the image, bounded image size) throws semap::Error naming `source` before anything
  /// is sized from the camera.
  void set_camera(const CameraModel& stored, const std::string& source);
  /// Frame i from its decoded images (metadata from records_[i]); checks the image sizes
  /// against the camera, errors naming `rgb_source`.
  Frame make_frame(size_t i, cv::Mat depth, cv::Mat rgb, const std::filesystem::path& rgb_source) const;
  /// Throws naming root_ when i is out of range.
  void check_index(size_t i) const;

  std::filesystem::path root_;
  CameraModel camera_;
  std::vector<FrameRecord> records_;

 private:
  std::shared_ptr<const LensUndistortion> undistortion_;
};

/// Detects the layout of `root` (dataset.yaml beside the data wins) and opens it: a folder
/// (TUM, 7-Scenes, YCB-Video, synthetic, ScanNet export) or a file (ROS1 .bag, ScanNet .sens).
/// Throws semap::Error naming the path when it is missing or no layout matches.
std::unique_ptr<DatasetReader> open_dataset(const std::filesystem::path& root);

struct DatasetOptions {
  /// Synthetic layout: read label_noisy.txt / instance_noisy.txt instead of the clean lists.
  bool noisy_labels = false;
  /// ROS bags: the colour and depth image topics (sensor_msgs/Image or CompressedImage).
  /// Empty = chosen automatically when the bag has exactly one of each.
  std::string rgb_topic;
  std::string depth_topic;
};
std::unique_ptr<DatasetReader> open_dataset(const std::filesystem::path& root, const DatasetOptions& options);

/// False when semap was built without the ROS bag libraries (a .bag then fails to open, saying so).
bool have_rosbag_support();

/// TUM RGB-D intrinsic presets (freiburg 1, 2 or 3), 640x480, depth scale 5000.
CameraModel tum_camera_preset(int freiburg);
/// YCB-Video object id (1..21) -> project class (mug -> cup, boxes/bricks -> box, bottles ->
/// bottle, bowl -> bowl, cans/tools/fruit -> other); 0 -> unlabelled.
ClassId ycb_to_project_class(int ycb_id);

}  // namespace semap
