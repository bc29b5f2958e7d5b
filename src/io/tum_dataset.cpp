// TUM RGB-D layout: rgb.txt + depth.txt (+ groundtruth.txt). Depth is registered to colour
// (one camera model), intrinsics from the fr1/fr2/fr3 preset named by the folder.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>

#include "semap/core/error.hpp"
#include "io/dataset_layouts.hpp"
#include "io/text_util.hpp"
#include "semap/io/trajectory_io.hpp"

namespace semap::io_detail {

namespace fs = std::filesystem;

namespace {

/// 1, 2 or 3 when `text` names a freiburg sequence ("freiburg2", "fr2", "rgbd_dataset_freiburg3_..."), else 0.
int freiburg_in(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  for (const std::string prefix : {"freiburg", "fr"}) {
    for (size_t pos = text.find(prefix); pos != std::string::npos; pos = text.find(prefix, pos + 1)) {
      const size_t digit = pos + prefix.size();
      // "fr1" must not be part of a longer word ("frame1") nor followed by more digits.
      const bool starts_word = pos == 0 || !std::isalpha(static_cast<unsigned char>(text[pos - 1]));
      if (!starts_word || digit >= text.size() || text[digit] < '1' || text[digit] > '3') continue;
      if (digit + 1 < text.size() && std::isdigit(static_cast<unsigned char>(text[digit + 1]))) continue;
      return text[digit] - '0';
    }
  }
  return 0;
}

}  // namespace

std::unique_ptr<DatasetReader> open_tum(const fs::path& root, const DatasetYaml* yaml) {
  const fs::path rgb_list = root / "rgb.txt", depth_list = root / "depth.txt";
  std::vector<FrameRecord> records = associate_lists(rgb_list, depth_list);

  CameraModel camera;
  if (yaml && yaml->camera) {
    camera = tum_camera_preset(1);
    camera.distortion = {0, 0, 0, 0, 0};  // a yaml camera names its own lens (camera.distortion)
    apply_yaml_camera(yaml, camera);
  } else {
    // The folder name, else the bag name in rgb.txt's header ("# file: 'rgbd_dataset_freiburg1_rpy.bag'").
    int freiburg = freiburg_in(fs::absolute(root).lexically_normal().filename().string());
    if (freiburg == 0) freiburg = freiburg_in(read_file_bytes(rgb_list).substr(0, 512));
    if (freiburg == 0) {
      spdlog::warn("{}: cannot tell fr1/fr2/fr3 from the folder name; using the freiburg1 intrinsics "
                   "(add a dataset.yaml to set them)", root.string());
      freiburg = 1;
    }
    camera = tum_camera_preset(freiburg);
  }
  if (fs::exists(root / "groundtruth.txt"))
    attach_ground_truth(records, read_tum_trajectory(root / "groundtruth.txt"), (root / "groundtruth.txt").string());
  return std::make_unique<LayoutDataset>("tum", root, camera, std::move(records));
}

}  // namespace semap::io_detail
