// Microsoft 7-Scenes layout: frame-XXXXXX.{color.jpg,depth.png,pose.txt} with optional
// TUM-style lists. Depth in mm, 0 and 65535 invalid; colour treated as registered to depth
// (the common approximation; 7-Scenes does not register them).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "semap/core/error.hpp"
#include "io/dataset_layouts.hpp"
#include "io/text_util.hpp"
#include "semap/io/trajectory_io.hpp"

namespace semap::io_detail {

namespace fs = std::filesystem;

namespace {

constexpr double kFrameRate = 30.0;  // 7-Scenes has no timestamps; frame index / 30 Hz

CameraModel read_intrinsics(const fs::path& root) {
  CameraModel camera;
  camera.depth = {585.0, 585.0, 320.0, 240.0, 640, 480};
  camera.depth_scale = 1000.0;
  const fs::path file = root / "camera-intrinsics.txt";
  if (!fs::exists(file)) return camera;
  const std::vector<double> m = read_numbers(file);
  for (double v : m)
    if (!std::isfinite(v)) throw Error(file, "NaN or Inf in the intrinsic matrix");
  if (m.size() != 9 || !(m[0] > 0 && m[4] > 0)) throw Error(file, "expected a 3x3 intrinsic matrix");
  camera.depth.fx = m[0], camera.depth.fy = m[4], camera.depth.cx = m[2], camera.depth.cy = m[5];
  return camera;
}

/// frame-XXXXXX.color.{jpg,png} files in index order.
std::vector<FrameRecord> scan_frames(const fs::path& root) {
  std::vector<std::pair<int, fs::path>> colour;
  for (const auto& entry : fs::directory_iterator(root)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("frame-", 0) != 0 || name.find(".color.") == std::string::npos) continue;
    colour.emplace_back(std::atoi(name.c_str() + 6), entry.path());
  }
  std::sort(colour.begin(), colour.end());
  std::vector<FrameRecord> records;
  for (const auto& [index, path] : colour) {
    std::string depth = path.filename().string();
    depth.replace(depth.find(".color."), std::string::npos, ".depth.png");
    FrameRecord r;
    r.timestamp = index / kFrameRate;
    r.rgb = path;
    r.depth = root / depth;
    if (!fs::exists(r.depth)) throw Error(r.depth, "depth image for " + path.filename().string() + " not found");
    records.push_back(std::move(r));
  }
  return records;
}

}  // namespace

std::unique_ptr<DatasetReader> open_7scenes(const fs::path& root, const DatasetYaml* yaml) {
  std::vector<FrameRecord> records;
  const fs::path associations = root / "associations.txt";
  if (fs::exists(associations)) {
    // "rgb_timestamp rgb_file depth_timestamp depth_file", as written by TUM's associate.py.
    for (const auto& e : read_list(associations, 3)) {
      FrameRecord r;
      r.timestamp = e.timestamp;
      r.rgb = listed_file(associations, e, 0);
      r.depth = listed_file(associations, e, 2);
      records.push_back(std::move(r));
    }
  } else if (fs::exists(root / "rgb.txt") || fs::exists(root / "depth.txt")) {
    records = associate_lists(root / "rgb.txt", root / "depth.txt");
  } else {
    records = scan_frames(root);
  }

  // Ground truth: the per-frame pose files (full precision), else groundtruth.txt.
  bool any_pose_file = false;
  for (auto& r : records) {
    std::string name = r.depth.filename().string();
    const size_t dot = name.find(".depth.");
    if (dot == std::string::npos) continue;
    const fs::path pose_file = r.depth.parent_path() / (name.substr(0, dot) + ".pose.txt");
    if (!fs::exists(pose_file)) continue;
    r.gt_T_world_camera = read_matrix_pose(pose_file);
    any_pose_file = true;
  }
  if (!any_pose_file && fs::exists(root / "groundtruth.txt"))
    attach_ground_truth(records, read_tum_trajectory(root / "groundtruth.txt"), (root / "groundtruth.txt").string());
  if (any_pose_file) use_local_origin_if_far(records, (root / "frame-*.pose.txt").string());

  CameraModel camera = read_intrinsics(root);
  if (!(yaml && yaml->camera) && fs::exists(root / "camera-intrinsics.txt"))
    validate_camera(camera, (root / "camera-intrinsics.txt").string());
  apply_yaml_camera(yaml, camera);
  return std::make_unique<LayoutDataset>("7scenes", root, camera, std::move(records));
}

}  // namespace semap::io_detail
