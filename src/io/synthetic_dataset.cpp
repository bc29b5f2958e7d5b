// The synthetic layout written by src/synth (SHARED_FORMATS.md): TUM lists for rgb, depth,
// label and instance images with identical timestamps, camera from dataset.yaml.
#include "semap/core/error.hpp"
#include "io/association.hpp"
#include "io/dataset_layouts.hpp"
#include "semap/io/trajectory_io.hpp"

namespace semap::io_detail {

namespace fs = std::filesystem;

namespace {

/// Sets `member` of every record from a list whose timestamps equal the frames'.
void attach_list(std::vector<FrameRecord>& records, const fs::path& list, fs::path FrameRecord::*member) {
  const auto entries = read_list(list);
  std::vector<double> frame_t, list_t;
  for (const auto& r : records) frame_t.push_back(r.timestamp);
  for (const auto& e : entries) list_t.push_back(e.timestamp);
  constexpr double kSameTimestamp = 1e-4;  // the writer uses the same stamps for every list
  const auto matches = associate_timestamps(frame_t, list_t, kSameTimestamp);
  if (matches.size() != records.size()) {
    size_t missing = 0;
    while (missing < matches.size() && matches[missing].first == missing) ++missing;
    throw Error(list, "no entry for the frame at timestamp " + std::to_string(records[missing].timestamp));
  }
  for (const auto& [i, j] : matches) records[i].*member = listed_file(list, entries[j], 0);
}

}  // namespace

std::unique_ptr<DatasetReader> open_synthetic(const fs::path& root, const DatasetYaml* yaml,
                                              const DatasetOptions& options) {
  if (!yaml || !yaml->camera) throw Error(root / "dataset.yaml", "the synthetic layout needs a 'camera' section");
  std::vector<FrameRecord> records = associate_lists(root / "rgb.txt", root / "depth.txt");
  const std::string suffix = options.noisy_labels ? "_noisy.txt" : ".txt";
  const fs::path labels = root / ("label" + suffix), instances = root / ("instance" + suffix);
  // Clean label lists are optional; asking for the noisy ones makes them required.
  if (options.noisy_labels || fs::exists(labels)) attach_list(records, labels, &FrameRecord::labels);
  if (options.noisy_labels || fs::exists(instances)) attach_list(records, instances, &FrameRecord::instances);
  if (fs::exists(root / "groundtruth.txt"))
    attach_ground_truth(records, read_tum_trajectory(root / "groundtruth.txt"), (root / "groundtruth.txt").string());
  CameraModel camera;
  apply_yaml_camera(yaml, camera);
  return std::make_unique<LayoutDataset>("synthetic", root, camera, std::move(records));
}

}  // namespace semap::io_detail
