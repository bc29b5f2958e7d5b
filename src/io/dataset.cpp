#include "semap/io/dataset.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>

#include "semap/core/error.hpp"
#include "core/lens_undistortion.hpp"
#include "core/paths.hpp"
#include "io/dataset_layouts.hpp"
#include "io/image_io.hpp"
#include "io/rosbag2_bag.hpp"
#include "io/rosbag_backend.hpp"

namespace semap {

namespace fs = std::filesystem;

namespace {

std::string size_text(cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }

bool has_file_named(const fs::path& dir, const std::string& prefix, const std::string& contains) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) == 0 && name.find(contains) != std::string::npos) return true;
  }
  return false;
}

bool is_ycb_layout(const fs::path& root) {
  if (has_file_named(root, "", "-color.png")) return true;
  std::error_code ec;
  for (fs::directory_iterator it(root / "data", ec), end; !ec && it != end; it.increment(ec))
    if (it->is_directory() && has_file_named(it->path(), "", "-color.png")) return true;
  return false;
}

/// Layout name from the files present; throws listing what was looked for.
std::string detect_layout(const fs::path& root) {
  // Not associations.txt alone: TUM users write one with associate.py too.
  if (fs::exists(root / "camera-intrinsics.txt") || has_file_named(root, "frame-", ".color."))
    return "7scenes";
  if (is_ycb_layout(root)) return "ycb";
  if (fs::exists(root / "scene.json") || fs::exists(root / "label.txt"))
    throw Error(root, "looks like the synthetic layout (scene.json/label.txt) but has no dataset.yaml naming the camera");
  if (fs::exists(root / "intrinsic" / "intrinsic_depth.txt")) return "scannet";
  if (fs::exists(root / "rgb.txt") || fs::exists(root / "depth.txt")) return "tum";
  throw Error(root, "no known dataset layout: looked for dataset.yaml, TUM (rgb.txt + depth.txt), 7-Scenes "
                    "(frame-XXXXXX.color.jpg / camera-intrinsics.txt), YCB-Video "
                    "(data/NNNN/XXXXXX-color.png), ScanNet export (intrinsic/intrinsic_depth.txt, color/, "
                    "depth/) and synthetic (dataset.yaml + label.txt)");
}

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

/// Single-file formats: ROS1 bags and ScanNet .sens recordings.
std::unique_ptr<DatasetReader> open_file(const fs::path& file, const DatasetOptions& options) {
  const std::string ext = lower_extension(file);
  if (ext == ".bag") return io_detail::open_rosbag(file, options);
  if (ext == ".db3" || ext == ".mcap") return io_detail::open_rosbag2(file, options);
  if (file.filename() == "metadata.yaml") return io_detail::open_rosbag2(file.parent_path(), options);  // a rosbag2 folder's
  if (ext == ".sens" && (!options.rgb_topic.empty() || !options.depth_topic.empty()))  // issue 44
    throw Error(file, "--rgb-topic / --depth-topic apply to ROS bags only; this is a ScanNet .sens file");
  if (ext == ".sens") return io_detail::open_scannet_sens(file);
  throw Error(file, "not a folder (expected a dataset folder, a ROS .bag, a rosbag2 .db3 / .mcap or a ScanNet .sens file)");
}

std::unique_ptr<DatasetReader> open_layout(const fs::path& root, const DatasetOptions& options);

}  // namespace

void DatasetReader::check_index(size_t i) const {
  if (i >= records_.size())
    throw Error(root_, "frame " + std::to_string(i) + " out of range (" + std::to_string(records_.size()) + " frames)");
}

void DatasetReader::set_camera(const CameraModel& stored, const std::string& source) {
  validate_camera(stored, source);  // before the undistortion maps are built from it
  undistortion_ = stored.has_distortion() ? std::make_shared<const LensUndistortion>(stored) : nullptr;
  camera_ = LensUndistortion::pinhole(stored);
}

Frame DatasetReader::load(size_t i) const {
  Frame frame = decode(i);
  if (undistortion_) undistortion_->apply(frame);
  return frame;
}

cv::Mat DatasetReader::load_depth(size_t i) const {
  cv::Mat depth = decode_depth(i);
  return undistortion_ ? undistortion_->depth(depth) : depth;
}

cv::Mat DatasetReader::decode_depth(size_t i) const {
  check_index(i);
  return read_depth_image(records_[i].depth, camera_.depth_scale, cv::Size(camera_.depth.width, camera_.depth.height));
}

Frame DatasetReader::make_frame(size_t i, cv::Mat depth, cv::Mat rgb, const fs::path& rgb_source) const {
  const FrameRecord& rec = records_[i];
  Frame frame;
  frame.index = i;
  frame.timestamp = rec.timestamp;
  frame.rgb_path = rec.rgb.string();
  frame.depth_path = rec.depth.string();
  frame.gt_T_world_camera = rec.gt_T_world_camera;
  frame.depth = std::move(depth);
  frame.rgb = std::move(rgb);
  if (!camera_.colour && frame.rgb.size() != frame.depth.size())
    throw Error(rgb_source, "RGB image is " + size_text(frame.rgb.size()) + " but depth image " + rec.depth.string() +
                                " is " + size_text(frame.depth.size()) + " (colour is registered to depth, sizes must match)");
  const PinholeIntrinsics& colour = camera_.colour_intrinsics();
  if (frame.rgb.size() != cv::Size(colour.width, colour.height))
    throw Error(rgb_source, "RGB image is " + size_text(frame.rgb.size()) + ", camera expects " +
                                size_text({colour.width, colour.height}));
  return frame;
}

Frame DatasetReader::decode(size_t i) const {
  cv::Mat depth = decode_depth(i);  // checks i
  const FrameRecord& rec = records_[i];
  Frame frame = make_frame(i, std::move(depth), read_colour_image(rec.rgb), rec.rgb);
  if (!rec.labels.empty()) {
    const cv::Mat raw = read_label_image(rec.labels, frame.rgb.size());
    double max_value = 0;
    cv::minMaxLoc(raw, nullptr, &max_value);
    if (max_value >= kNumClasses) throw Error(rec.labels, "class id " + std::to_string(int(max_value)) + " out of range");
    raw.convertTo(frame.labels, CV_8U);
  }
  if (!rec.instances.empty()) frame.instances = read_label_image(rec.instances, frame.rgb.size());
  return frame;
}

Trajectory DatasetReader::ground_truth() const {
  Trajectory trajectory;
  for (const auto& rec : records_)
    if (rec.gt_T_world_camera) trajectory.push_back({rec.timestamp, *rec.gt_T_world_camera});
  return trajectory;
}

bool DatasetReader::has_ground_truth() const {
  for (const auto& rec : records_)
    if (rec.gt_T_world_camera) return true;
  return false;
}

bool DatasetReader::has_label_ground_truth() const {
  return !records_.empty() && !records_.front().labels.empty();
}

std::unique_ptr<DatasetReader> open_dataset(const fs::path& root) { return open_dataset(root, DatasetOptions{}); }

std::unique_ptr<DatasetReader> open_dataset(const fs::path& folder, const DatasetOptions& options) {
  fs::path root = folder.lexically_normal();
  if (root.has_parent_path() && root.filename().empty()) root = root.parent_path();  // "dir/" -> "dir"
  std::error_code ec;
  const std::string ext = lower_extension(root);
  const bool file_format = ext == ".bag" || ext == ".sens" || ext == ".db3" || ext == ".mcap";
  if (!fs::exists(root, ec)) {  // "a dangling symlink (to X)" is not "not found" (issue 44)
    const std::string what = describe_path(root);
    if (what == "not found") throw Error(root, file_format ? "file not found" : "dataset folder not found");
    throw Error(root, std::string(file_format ? "dataset file" : "dataset folder") + " is " + what);
  }
  const bool is_folder = fs::is_directory(root, ec);
  if (is_folder && (ext == ".bag" || ext == ".sens"))  // a folder is reported as one (issue 44)
    throw Error(root, "is a folder, expected a " + ext + " file");
  if (!is_folder && !fs::is_regular_file(root, ec))
    throw Error(root, "not a folder or a regular file (expected a dataset folder, a .bag or a .sens file)");
  try {
    auto reader = is_folder ? open_layout(root, options) : open_file(root, options);
    if (reader->size() == 0) throw Error(root, "dataset has no frames");
    return reader;
  } catch (const fs::filesystem_error& e) {
    throw Error(e.path1().empty() ? root : e.path1(), e.code().message());
  }
}

namespace {
std::unique_ptr<DatasetReader> open_layout(const fs::path& root, const DatasetOptions& options) {
  std::optional<io_detail::DatasetYaml> yaml;
  if (fs::exists(root / "dataset.yaml")) yaml = io_detail::read_dataset_yaml(root / "dataset.yaml");
  if (!yaml && io_detail::is_rosbag2_folder(root)) return io_detail::open_rosbag2(root, options);
  if (!options.rgb_topic.empty() || !options.depth_topic.empty())  // issue 44: never silently ignored
    throw Error(root, "--rgb-topic / --depth-topic apply to ROS bags only; this is a dataset folder");
  const std::string layout = yaml && !yaml->format.empty() ? yaml->format : detect_layout(root);
  const io_detail::DatasetYaml* y = yaml ? &*yaml : nullptr;
  std::unique_ptr<DatasetReader> reader;
  if (layout == "tum") reader = io_detail::open_tum(root, y);
  else if (layout == "7scenes") reader = io_detail::open_7scenes(root, y);
  else if (layout == "ycb") reader = io_detail::open_ycb(root, y);
  else if (layout == "synthetic") reader = io_detail::open_synthetic(root, y, options);
  else if (layout == "scannet") reader = io_detail::open_scannet(root, y);
  else throw Error(root / "dataset.yaml", "unknown format '" + layout + "' (tum, 7scenes, ycb, synthetic, scannet)");
  if (reader->size() == 0) throw Error(root, "dataset has no frames");
  return reader;
}

}  // namespace

bool have_rosbag_support() { return io_detail::rosbag_backend::available(); }

CameraModel tum_camera_preset(int freiburg) {
  // Published TUM RGB-D calibrations with their lens distortion (depth scale 5000 = 1/5 mm).
  CameraModel camera;
  camera.depth_scale = 5000.0;
  switch (freiburg) {
    case 1:
      camera.depth = {517.3, 516.5, 318.6, 255.3, 640, 480};
      camera.distortion = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
      break;
    case 2:
      camera.depth = {520.9, 521.0, 325.1, 249.7, 640, 480};
      camera.distortion = {0.2312, -0.7849, -0.0033, -0.0001, 0.9172};
      break;
    // freiburg3's images were undistorted by TUM before release.
    case 3: camera.depth = {535.4, 539.2, 320.1, 247.6, 640, 480}; break;
    default: throw Error("tum_camera_preset", "freiburg must be 1, 2 or 3");
  }
  return camera;
}

ClassId ycb_to_project_class(int ycb_id) {
  // YCB-Video ids 1..21 (see the dataset's classes.txt).
  static constexpr Label kMap[22] = {
      Label::kUnlabelled,  // 0 background
      Label::kOther,       // 1 002_master_chef_can
      Label::kBox,         // 2 003_cracker_box
      Label::kBox,         // 3 004_sugar_box
      Label::kOther,       // 4 005_tomato_soup_can
      Label::kBottle,      // 5 006_mustard_bottle
      Label::kOther,       // 6 007_tuna_fish_can
      Label::kBox,         // 7 008_pudding_box
      Label::kBox,         // 8 009_gelatin_box
      Label::kOther,       // 9 010_potted_meat_can
      Label::kOther,       // 10 011_banana
      Label::kOther,       // 11 019_pitcher_base
      Label::kBottle,      // 12 021_bleach_cleanser
      Label::kBowl,        // 13 024_bowl
      Label::kCup,         // 14 025_mug
      Label::kOther,       // 15 035_power_drill
      Label::kBox,         // 16 036_wood_block
      Label::kOther,       // 17 037_scissors
      Label::kOther,       // 18 040_large_marker
      Label::kOther,       // 19 051_large_clamp
      Label::kOther,       // 20 052_extra_large_clamp
      Label::kBox,         // 21 061_foam_brick
  };
  if (ycb_id <= 0) return id(Label::kUnlabelled);
  return id(ycb_id < 22 ? kMap[ycb_id] : Label::kOther);
}

}  // namespace semap
