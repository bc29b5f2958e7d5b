#pragma once
// Helpers of the multi-session tests (issue 19): map a recording with run_pipeline (optionally
// resuming a saved map) and read files back.
#include <filesystem>
#include <fstream>
#include <string>

#include "semap/eval/trajectory_metrics.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "synth/synth_config.hpp"

namespace semap::test {

inline std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// `semap run DATASET --out OUT [--resume RESUME] [--segmenter SEGMENTER]` with 2 threads, no
/// progress lines; geometry only unless a segmenter is given (not the default models, issue 38).
inline RunResult map_recording(const std::filesystem::path& dataset, const std::filesystem::path& out,
                               const std::filesystem::path& resume = {}, const std::string& segmenter = "none") {
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

/// Two synthetic rooms of 30 frames at 320x240 in `dir`/room1 and `dir`/room2: the second of
/// another size, layout and textures (a place the first map never saw).
inline void write_two_rooms(const std::filesystem::path& dir) {
  SynthConfig synth;
  synth.frames = 30;
  synth.width = 320;
  synth.height = 240;
  synth.seed = 1;
  generate_dataset(synth, dir / "room1");
  synth.seed = 7;
  synth.room_x = 8.0;
  synth.room_y = 4.0;
  generate_dataset(synth, dir / "room2");
}

}  // namespace semap::test
