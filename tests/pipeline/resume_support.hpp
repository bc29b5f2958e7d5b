#pragma once
// Helpers of the multi-session tests (issue 19): map a recording with run_pipeline (optionally
// resuming a saved map) and read files back.
#include <filesystem>
#include <fstream>
#include <string>

#include "semap/eval/trajectory_metrics.hpp"
#include "semap/pipeline/run_pipeline.hpp"

namespace semap::test {

inline std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// `semap run DATASET --out OUT [--resume RESUME] [--segmenter SEGMENTER]` with 2 threads, no
/// progress lines.
inline RunResult map_recording(const std::filesystem::path& dataset, const std::filesystem::path& out,
                               const std::filesystem::path& resume = {}, const std::string& segmenter = "") {
  RunOptions options;
  options.segmenter = segmenter;
  options.dataset = dataset;
  options.out_dir = out;
  options.resume_from = resume;
  options.show_progress = false;
  SemapConfig config;
  config.pipeline.threads = 2;
  return run_pipeline(options, config);
}

}  // namespace semap::test
