// Determinism (issue 8). One thread: byte-identical outputs (tests/pipeline). More threads:
// the stages overlap and the object map sees frames in a timing-dependent order, so outputs
// may differ; the metrics must stay within the tolerances stated below of the one-thread run.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/progress.hpp"
#include "pipeline/mapper.hpp"
#include "synth/synth_config.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

// Stated tolerances of a multi-thread run against the one-thread run of the same input
// (60 synthetic frames, ground-truth poses, simulated segmentation with 10 % flicker).
// Measured (5 runs each of 2 and 4 threads): completeness and surface error identical, mIoU
// 0.835-0.883 against 0.890-0.893 with one thread (largest difference 0.058).
constexpr double kMiouTolerance = 0.08;           // semantic mIoU, absolute
constexpr double kCompletenessTolerance = 0.01;   // fraction of GT surface within 5 cm
constexpr double kSurfaceErrorTolerance = 0.001;  // m, mean map-to-GT distance
// Not asserted yet: the object map differs beyond any useful tolerance. With 2 or 4 threads
// it kept 1 object (WOv 0.145-0.155) where one thread keeps 3 (WOv 0.185-0.198) on this input, every run
// (the threaded pipeline hands the object map fewer frames; see summary.object_frames). The
// figures are printed so that the fix can tighten this test.

TEST(Determinism, MultiThreadMetricsMatchOneThreadWithinTolerance) {
  Progress::set_mode(-1);
  test::TempDir tmp("semap_determinism");
  SynthConfig synth;
  synth.frames = 60;
  synth.seed = 4;
  synth.objects = 6;
  synth.width = 160;
  synth.height = 120;
  generate_dataset(synth, tmp / "data");

  auto run = [&](int threads, const std::string& name) {
    SemapConfig config;
    config.pipeline.threads = threads;
    config.tsdf.voxel_size = 0.03;
    RunOptions o;
    o.dataset = tmp / "data";
    o.out_dir = tmp / name;
    o.poses = "groundtruth";
    o.segmenter = "groundtruth";
    o.seg_noise = 0.1;  // the simulated imperfect segmenter: labels differ per frame
    o.show_progress = false;
    return run_pipeline(o, config);
  };
  const nlohmann::json ref = run(1, "t1");
  const auto& rs = ref["evaluation"]["semantic"];
  const auto& ro = ref["evaluation"]["objects"];
  ASSERT_FALSE(rs.is_null());
  ASSERT_FALSE(ro.is_null());
  // The reference itself is a sensible map (else agreeing with it means little).
  EXPECT_GE(rs["miou"].get<double>(), 0.5);
  for (int threads : {2, 4}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    const nlohmann::json r = run(threads, "t" + std::to_string(threads));
    const auto& s = r["evaluation"]["semantic"];
    const auto& o = r["evaluation"]["objects"];
    EXPECT_EQ(r["summary"]["frames"], ref["summary"]["frames"]);
    EXPECT_EQ(r["summary"]["frames_skipped"], ref["summary"]["frames_skipped"]);
    EXPECT_NEAR(s["miou"].get<double>(), rs["miou"].get<double>(), kMiouTolerance);
    EXPECT_NEAR(s["completeness"].get<double>(), rs["completeness"].get<double>(), kCompletenessTolerance);
    EXPECT_NEAR(s["surface_error_mean_m"].get<double>(), rs["surface_error_mean_m"].get<double>(), kSurfaceErrorTolerance);
    std::printf("threads %d: mIoU %.4f (1 thread %.4f), completeness %.4f (%.4f), surface error %.4f (%.4f) m, "
                "WOv %.4f (%.4f), objects %d (%d), object frames %d (%d)\n",
                threads, s["miou"].get<double>(), rs["miou"].get<double>(), s["completeness"].get<double>(),
                rs["completeness"].get<double>(), s["surface_error_mean_m"].get<double>(),
                rs["surface_error_mean_m"].get<double>(), o["wov"].get<double>(), ro["wov"].get<double>(),
                r["summary"]["objects"].get<int>(), ref["summary"]["objects"].get<int>(),
                r["summary"]["object_frames"].get<int>(), ref["summary"]["object_frames"].get<int>());
  }
}

}  // namespace
}  // namespace semap
