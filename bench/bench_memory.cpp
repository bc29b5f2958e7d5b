// Long-run memory (issue 8): peak RSS, TSDF block count and object point count against the
// number of frames on a long synthetic sequence. The sequence is one rendered loop of
// --loop-frames images around the room, listed --frames / --loop-frames times over (the TUM
// lists repeat with shifted timestamps, so 10 000 frames need only one loop of PNGs). After
// the first loop the explored volume is fixed, so blocks, object points and RSS must stay flat;
// a last run with tsdf.drop_distance shows the configured max range freeing far blocks.
// Each point of the table is its own `semap run`-equivalent process (this program re-executed
// with --child), so its peak RSS is that run's own.
//   bench_memory [--frames 10000] [--loop-frames 500] [--width 160] [--height 120]
//                [--threads 2] [--drop-distance 3.0] [--out DIR]
// Prints one JSON object: {"rows": [{frames, peak_rss_mb, blocks, objects, object_points, wall_s}], ...}.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench_options.hpp"
#include "semap/core/error.hpp"
#include "core/progress.hpp"
#include "semap/eval/object_metrics.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "synth/synth_config.hpp"
#include "tsdf/map_io.hpp"

namespace fs = std::filesystem;
using namespace semap;

namespace {

/// Writes `list` of `loop_dir` into `long_dir`, repeated `times` times with timestamps shifted by
/// k * period and file names made relative to the loop folder.
void repeat_list(const fs::path& loop_dir, const fs::path& long_dir, const std::string& list, int times, double period) {
  std::ifstream in(loop_dir / list);
  if (!in) return;
  std::vector<std::pair<double, std::string>> rows;
  std::string header;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') {
      header += line + "\n";
      continue;
    }
    std::istringstream ls(line);
    double t;
    ls >> t;
    std::string rest, tok;
    while (ls >> tok) {
      // Image paths point back into the loop folder; pose numbers stay as they are.
      if (tok.find('/') != std::string::npos) tok = (loop_dir / tok).string();
      rest += " " + tok;
    }
    rows.emplace_back(t, rest);
  }
  std::ofstream out(long_dir / list);
  out << header;
  char stamp[64];
  for (int k = 0; k < times; ++k)
    for (const auto& [t, rest] : rows) {
      std::snprintf(stamp, sizeof stamp, "%.6f", t + k * period);
      out << stamp << rest << "\n";
    }
}

struct Args {
  size_t frames = 10000;
  int loop_frames = 500, width = 160, height = 120, threads = 2;
  double drop_distance = 3.0;  // about half of the 6 x 5 m synthetic room stays in the map
  fs::path out = fs::temp_directory_path() / "semap_bench_memory";
  // --child: one run
  size_t child_frames = 0;
  double child_drop = 0;
  fs::path child_dataset, child_out;
};

int run_child(const Args& a) {
  Progress::set_mode(-1);
  SemapConfig config;
  config.pipeline.threads = a.threads;
  config.tsdf.voxel_size = 0.04;
  config.tsdf.drop_distance = a.child_drop;
  RunOptions o;
  o.dataset = a.child_dataset;
  o.out_dir = a.child_out;
  o.poses = PoseSource::groundtruth;
  o.segmenter = "groundtruth";
  o.max_frames = a.child_frames;
  o.evaluate = false;
  o.show_progress = false;
  run_pipeline(o, config);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  const auto exit_code = bench::parse_options(
      argc, argv, 1,
      "[--frames 10000] [--loop-frames 500] [--width 160] [--height 120] [--threads 2]\n"
      "       [--drop-distance 3.0] [--out DIR]",
      [&](const std::string& k, const std::string& v) {
        if (k == "--frames") a.frames = std::stoul(v);
        else if (k == "--loop-frames") a.loop_frames = std::stoi(v);
        else if (k == "--width") a.width = std::stoi(v);
        else if (k == "--height") a.height = std::stoi(v);
        else if (k == "--threads") a.threads = std::stoi(v);
        else if (k == "--drop-distance") a.drop_distance = std::stod(v);
        else if (k == "--out") a.out = v;
        else if (k == "--child") a.child_frames = std::stoul(v);
        else if (k == "--child-drop") a.child_drop = std::stod(v);
        else if (k == "--child-dataset") a.child_dataset = v;
        else if (k == "--child-out") a.child_out = v;
        else return false;
        return true;
      });
  if (exit_code) return *exit_code;
  try {
    if (a.child_frames) return run_child(a);

    fs::remove_all(a.out);
    const fs::path loop_dir = a.out / "loop", long_dir = a.out / "long";
    SynthConfig synth;
    synth.frames = a.loop_frames;
    synth.width = a.width;
    synth.height = a.height;
    synth.seed = 5;
    std::fprintf(stderr, "bench_memory: rendering one loop of %d frames (%dx%d)\n", a.loop_frames, a.width, a.height);
    generate_dataset(synth, loop_dir);
    const int times = static_cast<int>((a.frames + a.loop_frames - 1) / a.loop_frames);
    const double period = a.loop_frames / synth.fps;
    fs::create_directories(long_dir);
    fs::copy_file(loop_dir / "dataset.yaml", long_dir / "dataset.yaml");
    for (const char* list : {"rgb.txt", "depth.txt", "label.txt", "instance.txt", "groundtruth.txt"})
      repeat_list(loop_dir, long_dir, list, times, period);

    std::vector<size_t> counts;
    for (size_t c : {size_t(a.loop_frames / 4), size_t(a.loop_frames / 2), size_t(a.loop_frames), 2 * size_t(a.loop_frames),
                     a.frames / 4, a.frames / 2, a.frames})
      if (c > 0 && c <= a.frames && (counts.empty() || c > counts.back())) counts.push_back(c);

    nlohmann::json rows = nlohmann::json::array();
    auto run = [&](size_t n, double drop) {
      const fs::path out = a.out / ("run_" + std::to_string(n) + (drop > 0 ? "_drop" : ""));
      std::string cmd = std::string("'") + fs::absolute(argv[0]).string() + "' --child " + std::to_string(n) +
                        " --child-drop " + std::to_string(drop) + " --threads " + std::to_string(a.threads) +
                        " --child-dataset '" + long_dir.string() + "' --child-out '" + out.string() + "'";
      std::fprintf(stderr, "bench_memory: %zu frames%s\n", n, drop > 0 ? " (drop_distance)" : "");
      if (std::system(cmd.c_str()) != 0) throw Error(out, "child run failed");
      std::ifstream rin(out / "report.json");
      const auto report = nlohmann::json::parse(rin);
      const auto objects = load_map_objects(out / "objects.json");
      size_t object_points = 0;
      for (const auto& o : objects) object_points += o.points.size();
      nlohmann::json row = {{"frames", n},
                            {"peak_rss_mb", report["summary"]["peak_rss_mb"]},
                            {"blocks", load_map(out / "map.semap").num_blocks()},
                            {"map_file_mb", fs::file_size(out / "map.semap") / (1024.0 * 1024.0)},
                            {"objects", objects.size()},
                            {"object_points", object_points},
                            {"wall_s", report["summary"]["wall_s"]},
                            {"drop_distance_m", drop}};
      std::fprintf(stderr, "  %s\n", row.dump().c_str());
      rows.push_back(row);
      fs::remove_all(out);
    };
    for (size_t n : counts) run(n, 0.0);
    if (a.drop_distance > 0) run(a.frames, a.drop_distance);

    nlohmann::json result = {{"bench", "memory"},
                             {"loop_frames", a.loop_frames},
                             {"image", std::to_string(a.width) + "x" + std::to_string(a.height)},
                             {"voxel_size_m", 0.04},
                             {"threads", a.threads},
                             {"poses", "groundtruth"},
                             {"segmenter", "groundtruth"},
                             {"rows", rows}};
    std::cout << result.dump(2) << std::endl;
    fs::remove_all(a.out);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_memory: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
