// YCB-Video layout: data/NNNN/XXXXXX-{color,depth,label}.png. Depth is registered to colour,
// so the one camera model carries the colour intrinsics. Label images hold YCB object ids:
// Frame.labels gets project classes (ycb_to_project_class), Frame.instances the raw YCB id.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <map>
#include <cmath>
#include <nlohmann/json.hpp>

#include "io/json_number.hpp"
#include "semap/core/error.hpp"
#include "io/dataset_layouts.hpp"
#include "io/text_util.hpp"
#include "core/json_text.hpp"

namespace semap::io_detail {

namespace fs = std::filesystem;

namespace {

constexpr double kFrameRate = 30.0;  // no timestamps in YCB-Video; frame number / 30 Hz

class YcbDataset : public LayoutDataset {
 public:
  using LayoutDataset::LayoutDataset;
  Frame decode(size_t i) const override {
    Frame frame = DatasetReader::decode(i);
    if (frame.labels.empty()) return frame;
    frame.labels.convertTo(frame.instances, CV_16U);  // raw YCB ids, one object each
    cv::Mat lut(1, 256, CV_8U);
    for (int v = 0; v < 256; ++v) lut.at<uint8_t>(v) = ycb_to_project_class(v);
    cv::LUT(frame.labels, lut, frame.labels);
    return frame;
  }
};

std::vector<std::pair<int, fs::path>> colour_images(const fs::path& dir) {
  std::vector<std::pair<int, fs::path>> found;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    const size_t suffix = name.rfind("-color.png");
    if (suffix == std::string::npos || suffix + 10 != name.size()) continue;
    found.emplace_back(std::atoi(name.c_str()), it->path());
  }
  std::sort(found.begin(), found.end());
  return found;
}

/// Folder holding the frames: `root` itself or its single data/NNNN video.
fs::path frames_folder(const fs::path& root) {
  if (!colour_images(root).empty()) return root;
  std::vector<fs::path> videos;
  for (const auto& entry : fs::directory_iterator(root / "data"))
    if (entry.is_directory() && !colour_images(entry.path()).empty()) videos.push_back(entry.path());
  if (videos.size() != 1)
    throw Error(root / "data", std::to_string(videos.size()) + " videos found; open one data/NNNN folder directly");
  return videos.front();
}

CameraModel read_camera(const fs::path& base, const fs::path& frames) {
  CameraModel camera;
  camera.depth = {1066.778, 1067.487, 312.9869, 241.3109, 640, 480};  // asus-uw colour camera
  camera.depth_scale = 10000.0;
  const fs::path derived = base / "derived" / "intrinsics.txt";
  if (fs::exists(derived)) {
    const std::string text = read_file_bytes(derived, kMaxTextFileBytes, "intrinsics file");
    for_each_line(text, [&](std::string_view line, size_t line_no) {
      if (is_blank_or_comment(line)) return;
      const auto f = split_fields(line);
      const auto v = f.size() == 2 ? parse_double(f[1]) : std::nullopt;
      if (!v || !std::isfinite(*v) || *v <= 0) throw Error(where(derived.string(), line_no), "expected 'key positive-number'");
      if (f[0] == "fx") camera.depth.fx = *v;
      else if (f[0] == "fy") camera.depth.fy = *v;
      else if (f[0] == "cx") camera.depth.cx = *v;
      else if (f[0] == "cy") camera.depth.cy = *v;
      else if (f[0] == "factor_depth") camera.depth_scale = *v;
    });
    validate_camera(camera, derived.string());
    return camera;
  }
  // Videos 0000-0059 were taken with asus-uw, 0060-0091 with asus-cmu; camera[0] is colour.
  const int video = std::atoi(frames.filename().string().c_str());
  const fs::path json_file = base / "cameras" / (video >= 60 ? "asus-cmu.json" : "asus-uw.json");
  if (!fs::exists(json_file)) return camera;
  try {
    const auto json = nlohmann::json::parse(read_file_bytes(json_file, kMaxTextFileBytes, "camera file"));
    const auto& model = json.at("rig").at("camera").at(0).at("camera_model");
    const auto params = model.at("params").get<std::vector<double>>();
    if (params.size() < 4) throw Error(json_file, "camera params need fu fv u0 v0");
    camera.depth = {params[0], params[1], params[2], params[3], static_cast<int>(json_number(model.at("width"), "width", 0, 1e6, true)),
                    static_cast<int>(json_number(model.at("height"), "height", 0, 1e6, true))};
  } catch (const nlohmann::json::exception& e) {
    throw Error(json_file, "malformed camera JSON: " + json_error_text(e));
  }
  validate_camera(camera, json_file.string());
  return camera;
}

/// derived/camera_rotation_translation.txt: "frame r11 r12 r13 t1 ... t3", the world-to-camera
/// [R|t] of meta.mat (checked: inverse(RT) * object pose is constant over frames).
std::map<int, Pose> read_camera_poses(const fs::path& file) {
  std::map<int, Pose> poses;
  const std::string text = read_file_bytes(file, kMaxTextFileBytes, "pose file");
  for_each_line(text, [&](std::string_view line, size_t line_no) {
    if (is_blank_or_comment(line)) return;
    const auto f = split_fields(line);
    if (f.size() != 13) throw Error(where(file.string(), line_no), "expected 'frame' and 12 numbers");
    std::vector<double> m;
    for (size_t k = 1; k < 13; ++k) {
      const auto v = parse_double(f[k]);
      if (!v || !std::isfinite(*v)) throw Error(where(file.string(), line_no), "malformed number");
      m.push_back(*v);
    }
    poses[std::atoi(std::string(f[0]).c_str())] = pose_from_rows(m, where(file.string(), line_no)).inverse();
  });
  return poses;
}

}  // namespace

std::unique_ptr<DatasetReader> open_ycb(const fs::path& root, const DatasetYaml* yaml) {
  const fs::path frames = frames_folder(root);
  // derived/ and cameras/ live in the dataset root (or two levels above a video folder).
  const fs::path base =
      frames == root && !fs::exists(root / "derived") ? fs::absolute(root).parent_path().parent_path() : root;
  std::map<int, Pose> poses;
  const fs::path pose_file = base / "derived" / "camera_rotation_translation.txt";
  if (fs::exists(pose_file)) {
    try {
      poses = read_camera_poses(pose_file);
    } catch (const Error& e) {
      spdlog::warn("{} (ground-truth camera poses ignored)", e.what());
    }
  }
  std::vector<FrameRecord> records;
  for (const auto& [number, colour] : colour_images(frames)) {
    const std::string stem = colour.filename().string().substr(0, colour.filename().string().size() - 10);
    FrameRecord r;
    r.timestamp = number / kFrameRate;
    r.rgb = colour;
    r.depth = frames / (stem + "-depth.png");
    if (!fs::exists(r.depth)) throw Error(r.depth, "depth image for " + colour.filename().string() + " not found");
    if (fs::exists(frames / (stem + "-label.png"))) r.labels = frames / (stem + "-label.png");
    if (auto it = poses.find(number); it != poses.end()) r.gt_T_world_camera = it->second;
    records.push_back(std::move(r));
  }
  use_local_origin_if_far(records, pose_file.string());
  CameraModel camera = read_camera(base, frames);
  apply_yaml_camera(yaml, camera);
  return std::make_unique<YcbDataset>("ycb", root, camera, std::move(records));
}

}  // namespace semap::io_detail
