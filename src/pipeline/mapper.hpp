#pragma once
// The Mapper facade: frames -> tracking/segmentation -> TSDF fusion + object map -> outputs.
// Stages run on their own threads joined by bounded queues (tracking on every frame,
// segmentation asynchronously on every N-th frame/keyframe, TSDF integration, object
// mapping); nothing waits on the network. A final pose-graph pass refreshes the map.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "pipeline/semap_config.hpp"

namespace semap {

struct RunOptions {
  std::filesystem::path dataset;
  std::filesystem::path out_dir;
  std::string poses = "track";          ///< "track" or "groundtruth"
  std::string segmenter = "groundtruth"; ///< "yolo:PATH" | "semantic:PATH" | "groundtruth" | "none"
  double seg_noise = 0.0;               ///< > 0: built-in noisy segmentation of ground-truth labels (flicker rate)
  size_t max_frames = 0;                ///< 0 = all
  bool evaluate = true;                 ///< run `semap eval` figures when ground truth exists
  bool show_progress = true;
};

/// Runs the whole pipeline and writes every output into options.out_dir (atomically).
/// Returns the report (also written as report.json). Throws semap::Error on bad input.
nlohmann::json run_pipeline(const RunOptions& options, const SemapConfig& config);

}  // namespace semap
