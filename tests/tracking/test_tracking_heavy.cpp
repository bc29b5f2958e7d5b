// Longer tracking runs (LABELS heavy): 7-Scenes redkitchen 500 frames and a synthetic closed
// loop with depth noise, with and without loop closure (issue 4 figures).
#include <gtest/gtest.h>

#include "synth/synth_config.hpp"
#include "test_support.hpp"
#include "tracking/tracking_test_util.hpp"

using namespace semap;

// Issue 4 target; not met yet (see the tracking report): fails until tracking improves.
TEST(TrackingHeavy, TumFr1Rpy200IssueTarget) {
  SEMAP_REQUIRE_DATA(dir, "tum_fr1_rpy");
  TrackingConfig config;
  config.background_loop_closure = false;
  const auto run = test::run_tracker_on(dir, 200, config);
  EXPECT_LE(run.ate_rmse, 0.025);
}

TEST(TrackingHeavy, SevenScenesRedkitchen500) {
  SEMAP_REQUIRE_DATA(dir, "7scenes_redkitchen");
  TrackingConfig config;
  config.background_loop_closure = false;
  const auto run = test::run_tracker_on(dir, 500, config);
  EXPECT_LE(run.ate_rmse, 0.04);
}

TEST(TrackingHeavy, SyntheticLoopWithDepthNoiseLoopClosureHelps) {
  test::TempDir tmp("semap_tracking_synth");
  SynthConfig synth;
  synth.frames = 300;
  synth.seed = 3;
  synth.depth_noise = true;
  generate_dataset(synth, tmp / "loop");
  TrackingConfig full;
  full.background_loop_closure = false;
  const auto with_loops = test::run_tracker_on(tmp / "loop", 300, full);
  TrackingConfig odometry = full;
  odometry.pose_graph = false;
  odometry.keyframe_reuse = false;
  const auto odometry_only = test::run_tracker_on(tmp / "loop", 300, odometry);
  std::cout << "[tracking] synthetic loop ATE with loop closure " << with_loops.ate_rmse * 100
            << " cm, odometry only " << odometry_only.ate_rmse * 100 << " cm" << std::endl;
  EXPECT_LE(with_loops.ate_rmse, 0.01);
  EXPECT_GE(with_loops.stats.loop_edges + with_loops.stats.keyframe_reuses, 1u);
  EXPECT_LT(with_loops.ate_rmse, 0.9 * odometry_only.ate_rmse);
}
