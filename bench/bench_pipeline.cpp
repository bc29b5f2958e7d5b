// bench_pipeline: `semap run` end to end (the library's run_pipeline, default configuration,
// 2 threads) with the per-stage CPU budget of issue 20. Prints JSON: fps online, and per
// stage the CPU ms per frame read (the stage's own thread plus the TBB workers of its
// parallel loops, as StageTimings records them), their sum, the process CPU of the streaming
// part, and the budget threads x 1000 / target fps ms per frame.
//
//   build/bench/bench_pipeline DATASET [--segmenter none|yolo:MODEL|...] [--frames N] [--threads 2]
//                              [--target-fps 30] [--config FILE]
//
// Stages: read (decoding, the prefetch thread), tracking (+ depth repair), integration (colour
// registration, the TSDF with its arena's workers, the refresh archive), segmentation (the
// segmenter's thread; a panoptic segmenter's instance network) and semantic_segmentation (a
// panoptic segmenter's semantic network on its own thread and schedule, issue 38), objects
// (object map keyframes + accumulation), and OpenCV's worker threads (cv::parallel_for_ of any
// stage: the network, image operations; not split by stage).
// The objects stage may still drain queued keyframes after reading ended: its CPU is counted
// whole, so the sum can exceed the process CPU of the streaming part.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <unistd.h>

#include "bench/bench_options.hpp"
#include "semap/pipeline/run_pipeline.hpp"

using namespace semap;
namespace fs = std::filesystem;

namespace {

struct BudgetStage {
  const char* name;
  std::vector<const char*> timings;  ///< StageTimings entries that make it up
};

const std::vector<BudgetStage> kStages = {
    {"read", {"read"}},
    {"tracking", {"tracking", "depth_repair"}},
    {"integration", {"tsdf_integration"}},  // refresh_archive runs inside it
    {"segmentation", {"segmentation"}},                    // the segmenter, or a panoptic one's instance network
    {"semantic_segmentation", {"semantic_segmentation"}},  // a panoptic segmenter's semantic network
    {"objects", {"object_map", "object_accumulate"}},
};

}  // namespace

int main(int argc, char** argv) {
  constexpr const char* kUsage = "DATASET [--segmenter SPEC] [--frames N] [--threads N] [--target-fps F] [--config FILE]";
  if (argc < 2 || argv[1][0] == '-') {  // no DATASET: the usage, on stdout when asked for
    const bool help = argc >= 2 && (std::string_view(argv[1]) == "--help" || std::string_view(argv[1]) == "-h");
    (help ? std::cout : std::cerr) << "usage: bench_pipeline " << kUsage << "\n";
    return help ? 0 : 2;
  }
  RunOptions options;
  options.dataset = argv[1];
  options.show_progress = false;
  options.evaluate = false;
  int threads = 2;
  double target_fps = 30;
  fs::path config_path;
  const auto exit_code = bench::parse_options(argc, argv, 2, kUsage, [&](const std::string& a, const std::string& v) {
    if (a == "--segmenter") options.segmenter = v;
    else if (a == "--frames") options.max_frames = std::stoul(v);
    else if (a == "--threads") threads = std::stoi(v);
    else if (a == "--target-fps") target_fps = std::stod(v);
    else if (a == "--config") config_path = v;
    else return false;
    return true;
  });
  if (exit_code) return *exit_code;
  SemapConfig config = load_semap_config(config_path);
  config.pipeline.threads = threads;
  options.out_dir = fs::temp_directory_path() / ("bench_pipeline_" + std::to_string(::getpid()));
  const RunResult r = run_pipeline(options, config);
  fs::remove_all(options.out_dir);

  const double frames = static_cast<double>(std::max<size_t>(1, r.frames_read + r.frames_skipped));
  nlohmann::json stages = nlohmann::json::object();
  double sum = 0;
  for (const BudgetStage& stage : kStages) {
    double cpu = 0, wall = 0;
    for (const char* name : stage.timings)
      if (const auto it = r.timings.find(name); it != r.timings.end()) cpu += it->second.cpu_total_ms, wall += it->second.total_ms;
    stages[stage.name] = {{"cpu_ms_per_frame", cpu / frames}, {"wall_ms_per_frame", wall / frames}};
    sum += cpu / frames;
  }
  const double opencv_workers = r.cpu_s_online_opencv_workers * 1e3 / frames;
  stages["opencv_workers"] = {{"cpu_ms_per_frame", opencv_workers}};
  sum += opencv_workers;
  const double budget = threads * 1e3 / target_fps;
  nlohmann::json out;
  out["dataset"] = r.dataset;
  out["segmenter"] = r.mapper.segmenter;
  out["frames"] = r.frames_read + r.frames_skipped;
  out["segmented_frames"] = r.mapper.segmented_frames;
  out["semantic_segmented_frames"] = r.mapper.semantic_segmented_frames;
  out["threads"] = threads;
  out["fps_online"] = r.fps_online;
  out["fps_end_to_end"] = r.fps_end_to_end;
  out["stages"] = stages;
  out["stage_cpu_sum_ms_per_frame"] = sum;
  out["process_cpu_ms_per_frame_online"] = r.cpu_s_online * 1e3 / frames;
  out["target_fps"] = target_fps;
  out["budget_ms_per_frame"] = budget;  // threads cores x 1000 / target fps
  out["within_budget"] = sum < budget;
  std::string bottleneck;
  double most = -1;
  for (const auto& [name, s] : stages.items())
    if (s["cpu_ms_per_frame"].get<double>() > most) most = s["cpu_ms_per_frame"], bottleneck = name;
  out["bottleneck"] = bottleneck;
  out["peak_rss_mb"] = r.peak_rss_mb;
  std::cout << out.dump(2) << std::endl;
  return 0;
}
