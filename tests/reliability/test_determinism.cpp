// Determinism (issue 8). One thread: byte-identical outputs (tests/pipeline). More threads:
// the stages overlap and the object map sees frames in a timing-dependent order, so outputs
// may differ; the metrics must stay within the tolerances stated below of the one-thread run.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/progress.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "synth/synth_config.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

// Stated tolerances of a multi-thread run against the one-thread run of the same input
// (60 synthetic frames at 320x240, ground-truth poses, simulated segmentation with 10 % flicker).
// Before the test gave the segmentation queue room for every frame, dropped requests made
// mIoU differ by up to 0.058 (5 runs each of 2 and 4 threads); without drops it is identical.
constexpr double kMiouTolerance = 0.02;           // semantic mIoU, absolute
constexpr double kCompletenessTolerance = 0.01;   // fraction of GT surface within 5 cm
constexpr double kSurfaceErrorTolerance = 0.001;  // m, mean map-to-GT distance
constexpr double kWovTolerance = 0.02;            // object map weighted overlap
// Measured with no dropped segmentation request: 1, 2 and 4 threads gave identical figures
// (320x240: mIoU 0.8810, WOv 0.838 by surface IoU (0.738 by voxel sets), 7 objects for 6; at 160x120 the reference map itself was
// poor, WOv 0.20 with 3 objects, and agreeing with it meant little). Dropped requests (the pipeline never stalls tracking
// for a busy segmenter) do change the object map: 4 threads once dropped one of 12 object
// frames and kept 1 object instead of 3.

TEST(Determinism, MultiThreadMetricsMatchOneThreadWithinTolerance) {
  Progress::set_mode(-1);
  test::TempDir tmp("semap_determinism");
  SynthConfig synth;
  synth.frames = 60;
  synth.seed = 4;
  synth.objects = 6;
  synth.width = 320;
  synth.height = 240;
  generate_dataset(synth, tmp / "data");

  auto run = [&](int threads, const std::string& name) {
    SemapConfig config;
    config.pipeline.threads = threads;
    config.tsdf.voxel_size = 0.03;
    // Room for every frame in the segmentation queue: no request is dropped for a busy
    // segmenter (the non-blocking hand-off of the threaded pipeline), so the thread counts
    // differ only in the order of parallel work, which is what this test measures.
    config.segmentation.async_queue_size = 64;
    RunOptions o;
    o.dataset = tmp / "data";
    o.out_dir = tmp / name;
    o.poses = PoseSource::groundtruth;
    o.segmenter = "groundtruth";
    o.seg_noise = 0.1;  // the simulated imperfect segmenter: labels differ per frame
    o.show_progress = false;
    return run_pipeline(o, config);
  };
  const RunResult ref = run(1, "t1");
  ASSERT_TRUE(ref.evaluation.semantic);
  ASSERT_TRUE(ref.evaluation.objects);
  const SemanticEvaluation& rs = *ref.evaluation.semantic;
  const ObjectEvaluation& ro = *ref.evaluation.objects;
  // The reference itself is a sensible map (else agreeing with it means little).
  EXPECT_GE(rs.miou, 0.8);   // measured 0.881
  EXPECT_GE(ro.wov, 0.75);   // measured 0.838
  EXPECT_LE(ref.mapper.objects, 8u);  // 7 for 6 objects
  for (int threads : {2, 4}) {
    SCOPED_TRACE("threads " + std::to_string(threads));
    const RunResult r = run(threads, "t" + std::to_string(threads));
    const SemanticEvaluation& s = r.evaluation.semantic.value();
    const ObjectEvaluation& o = r.evaluation.objects.value();
    EXPECT_EQ(r.frames_read, ref.frames_read);
    EXPECT_EQ(r.frames_skipped, ref.frames_skipped);
    EXPECT_EQ(r.mapper.segmentations_dropped, 0u);
    EXPECT_EQ(r.mapper.object_frames, ref.mapper.object_frames);
    EXPECT_NEAR(s.miou, rs.miou, kMiouTolerance);
    EXPECT_NEAR(s.completeness, rs.completeness, kCompletenessTolerance);
    EXPECT_NEAR(o.wov, ro.wov, kWovTolerance);
    EXPECT_EQ(r.mapper.objects, ref.mapper.objects);
    EXPECT_NEAR(s.surface_error_mean_m, rs.surface_error_mean_m, kSurfaceErrorTolerance);
    std::printf("threads %d: mIoU %.4f (1 thread %.4f), completeness %.4f (%.4f), surface error %.4f (%.4f) m, "
                "WOv %.4f (%.4f), objects %zu (%zu), object frames %zu (%zu)\n",
                threads, s.miou, rs.miou, s.completeness, rs.completeness, s.surface_error_mean_m,
                rs.surface_error_mean_m, o.wov, ro.wov, r.mapper.objects, ref.mapper.objects, r.mapper.object_frames,
                ref.mapper.object_frames);
  }
}

}  // namespace
}  // namespace semap
