// Issue 22 cases of `semap run` through its own wiring:
// its output folder through io/output_folder.hpp (staging + publish, stale objects/<id>.ply
// removed, Ctrl-C publishes nothing), `--max-frames -1`, `--voxel nan`, config magnitudes with
// lower bounds that bound memory, and runs where every frame is skipped or every segmentation
// fails.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>

#include "io/output_folder.hpp"
#include "reliability/reliability_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::expect_one_line_error;
using test::run_semap;
using test::slurp;
using test::spit;
using test::changes;
using test::snapshot;
using test::tree;
using test::visible;

class RunHardening : public test::CliSuite {
 protected:
  static void SetUpTestSuite() { make_suite("semap_run_hardening"); }
};

// ------------------------------------------------------------ Data loss and writes where they must not go

TEST_F(RunHardening, ASecondRunFailingMidwayLeavesTheFirstRunExactlyAsItWas) {
  const fs::path out = path("twice_out");
  ASSERT_EQ(run_semap(run_args(clean(), out)).exit_code, 0);
  const auto before = snapshot(out);
  // Every segmentation fails (an empty precomputed folder): the run fails after tracking and
  // fusing started, and nothing of it may appear beside the first run's report.
  fs::create_directories(path("empty_precomputed"));
  const auto r = run_semap(run_args(clean(), out, {"--segmenter", "precomputed:" + path("empty_precomputed").string()}));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(changes(before, snapshot(out)), "");
}

TEST_F(RunHardening, ASuccessfulSecondRunRemovesTheStaleFilesOfTheFirst) {
  const fs::path out = path("stale_out");
  ASSERT_EQ(run_semap(run_args(clean(), out)).exit_code, 0);
  const auto r = run_semap(run_args(clean(), out, {"--max-frames", "2"}));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Every objects/<id>.ply is one of objects.json's objects, and the manifest lists exactly
  // the files present.
  const auto objects = nlohmann::json::parse(slurp(out / "objects.json"))["objects"];
  std::set<std::string> listed;
  for (const auto& o : objects)
    if (o.contains("points_file")) listed.insert(o["points_file"].get<std::string>());
  for (const auto& f : visible(out))
    if (f.rfind("objects/", 0) == 0) EXPECT_TRUE(listed.count(f)) << f << " is stale";
  const auto manifest = OutputFolder::read_manifest(out, "run");
  EXPECT_EQ(std::set<std::string>(manifest.begin(), manifest.end()), visible(out));
}

/// A snapshot without semap's internal names (staging folders, manifests, markers).
std::map<std::string, std::string> visible_files(const std::map<std::string, std::string>& files) {
  std::map<std::string, std::string> out;
  for (const auto& [name, bytes] : files)
    if (!OutputFolder::is_internal_name(fs::path(name).begin()->string())) out[name] = bytes;
  return out;
}

TEST_F(RunHardening, CtrlCLeavesNothingThatLooksComplete) {
  // A longer sequence; a full run takes T seconds. One SIGINT at T/2: the run stops reading,
  // finishes the map and publishes it (exit 0, complete outputs). Two SIGINTs as soon as the
  // first output file appears: the run quits and publishes nothing (exit 130, every visible
  // file exactly as before: no map.semap.tmp, no new trajectory beside an old report; only its
  // hidden staging folder may remain, which the next run on the folder removes) or, when the
  // publish had already begun (signals wait for it), finishes it (exit 0).
  // Its ground-truth samples are unused here: coarse ones keep the dataset quick to make under
  // ASan, where the default 1 cm samples made `semap synth` alone pass CI's 120 s limit (stop 26).
  const fs::path longer = path("longer"), coarse_gt = path("coarse_gt.yaml");
  spit(coarse_gt, "synth:\n  gt_point_spacing: 0.1\n");
  ASSERT_EQ(run_semap({"synth", "--config", coarse_gt.string(), "--out", longer.string(), "--frames", "200", "--width",
                       "160", "--height", "120"},
                      600)
                .exit_code,
            0);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(run_semap(run_args(longer, path("ctrl_c_reference")), 600).exit_code, 0);
  const double full_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // The first file of the output phase (not the folder's marker nor a staging marker).
  const auto output_started = [](const fs::path& out, const std::map<std::string, std::string>& before) {
    for (const auto& f : tree(out)) {
      const std::string name = fs::path(f).filename().string();
      if (!before.count(f) && !OutputFolder::is_internal_name(name)) return true;
    }
    return false;
  };
  size_t interrupted = 0;
  for (const double fraction : {0.5, -1.0}) {  // -1: at the first output file
    for (const bool earlier_run : {false, true}) {
      SCOPED_TRACE(std::to_string(fraction) + (earlier_run ? " over a complete earlier run" : " into a new folder"));
      const fs::path out = path("ctrl_c_" + std::to_string(interrupted) + (earlier_run ? "_again" : "_new"));
      fs::remove_all(out);
      if (earlier_run) ASSERT_EQ(run_semap(run_args(clean(), out)).exit_code, 0);
      const auto before = snapshot(out);
      const pid_t pid = test::spawn_semap(run_args(longer, out), path("ctrl_c.log"));
      if (fraction > 0) {
        std::this_thread::sleep_for(std::chrono::duration<double>(fraction * full_s));
      } else {
        const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(2 * full_s + 10);
        while (!output_started(out, before) && std::chrono::steady_clock::now() < until)
          std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
      ::kill(pid, SIGINT);
      if (fraction < 0) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        ::kill(pid, SIGINT);
      }
      const int code = test::wait_exit(pid, std::max(120.0, 3 * full_s + 30));  // a slow machine, a loaded one
      if (code == 0) {
        EXPECT_TRUE(fs::exists(out / "report.json"));
        EXPECT_FALSE(OutputFolder::read_manifest(out, "run").empty());
        continue;
      }
      ++interrupted;
      EXPECT_LT(fraction, 0) << "one Ctrl-C must finish the map and publish it:\n" << slurp(path("ctrl_c.log"));
      EXPECT_EQ(code, 130) << slurp(path("ctrl_c.log"));
      EXPECT_EQ(changes(visible_files(before), visible_files(snapshot(out))), "");
    }
  }
  EXPECT_GT(interrupted, 0u);
}

TEST_F(RunHardening, APlantedObjectsSymlinkIsRefusedNotWrittenThrough) {
  const fs::path out = path("planted_objects"), outside = path("objects_outside");
  fs::create_directories(out);
  fs::create_directories(outside);
  fs::create_directory_symlink(outside, out / "objects");
  const auto r = run_semap(run_args(clean(), out));
  expect_one_line_error(r, {"objects", "symlink"});
  EXPECT_TRUE(fs::is_empty(outside));
}

// ------------------------------------------------------------ Crashes, hangs, memory

TEST_F(RunHardening, ConfigMagnitudesThatExplodeMemoryOrCrashPclAreErrors) {
  const fs::path cfg = path("cfg");
  fs::create_directories(cfg);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"objects:\n  voxel_resolution: 1e-9\n", "objects.voxel_resolution"},
      {"tsdf:\n  voxel_size: 1e-6\n", "tsdf.voxel_size"},
  };
  for (const auto& [yaml, key] : cases) {
    SCOPED_TRACE(key);
    spit(cfg / "c.yaml", yaml);
    const auto t0 = std::chrono::steady_clock::now();
    auto args = run_args(clean(), path("cfg_out"));
    args.erase(std::find(args.begin(), args.end(), "--voxel"), std::find(args.begin(), args.end(), "--voxel") + 2);
    args.insert(args.end(), {"--config", (cfg / "c.yaml").string()});
    expect_one_line_error(run_semap(args, 60), {"c.yaml", key});
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 20.0);
  }
  expect_one_line_error(run_semap(run_args(clean(), path("cfg_out"), {"--voxel", "1e-6"}), 60), {"--voxel"});
}

// ------------------------------------------------------------ Silent wrong results and unclear errors

TEST_F(RunHardening, MaxFramesMinusOneAndVoxelNanAreErrors) {
  expect_one_line_error(run_semap(run_args(clean(), path("flags_out"), {"--max-frames", "-1"})), {"--max-frames"});
  auto args = run_args(clean(), path("flags_out"));
  *(std::find(args.begin(), args.end(), "--voxel") + 1) = "nan";
  expect_one_line_error(run_semap(args), {"--voxel"});
  EXPECT_TRUE(tree(path("flags_out")).empty());
}

TEST_F(RunHardening, ARunWhereEveryFrameIsSkippedOrEverySegmentationFailsFails) {
  // dataset.yaml says 320x240 for 160x120 images: every frame is skipped.
  const fs::path d = path("wrong_size");
  fs::copy(clean(), d, fs::copy_options::recursive);
  std::string yaml = slurp(d / "dataset.yaml");
  yaml = std::regex_replace(yaml, std::regex("width: 160"), "width: 320");
  yaml = std::regex_replace(yaml, std::regex("height: 120"), "height: 240");
  spit(d / "dataset.yaml", yaml);
  const auto skipped = run_semap(run_args(d, path("wrong_size_out")));
  expect_one_line_error(skipped, {"frame"});
  EXPECT_TRUE(tree(path("wrong_size_out")).empty()) << "no empty mesh published";
  fs::create_directories(path("no_segmentations"));
  const auto failed = run_semap(run_args(clean(), path("no_seg_out"),
                                         {"--segmenter", "precomputed:" + path("no_segmentations").string()}));
  expect_one_line_error(failed, {"segment"});
  EXPECT_TRUE(tree(path("no_seg_out")).empty());
}

}  // namespace
}  // namespace semap
