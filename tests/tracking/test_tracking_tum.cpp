// TUM fr1_rpy, first 200 frames, tracked without ground truth. Fast regression guard (measured
// 2.0 cm ATE with the joint photometric + geometric ICP, 7.8 cm with geometry alone); the issue-4
// figures (<= 2.5 cm and lower than Open3D) are asserted by TrackingHeavy.TumFr1Rpy200IssueTarget.
#include <gtest/gtest.h>

#include "test_support.hpp"
#include "tracking/tracking_test_util.hpp"

using namespace semap;

TEST(TrackingDatasets, TumFr1Rpy200RegressionGuard) {
  SEMAP_REQUIRE_DATA(dir, "tum_fr1_rpy");
  TrackingConfig config;
  config.background_loop_closure = false;  // deterministic
  const auto run = test::run_tracker_on(dir, 200, config);
  // Issue 42: keyframe reuse verified like a kept reference: 1.89 -> 1.46 cm, 2.55 -> 2.03 deg/s.
  EXPECT_LE(run.ate_rmse, 0.02);   // the issue-42 target (measured 1.46 cm)
  EXPECT_LE(run.rpe_trans, 0.05);  // m/s over 1 s (measured 3.1 cm/s); a drifting tracker gives 6-7 (Open3D)
  EXPECT_LE(run.rpe_rot, 2.3);     // deg/s (measured 2.03; unverified reuses gave 2.55)
  EXPECT_LE(run.lost, 10u);
  EXPECT_GE(run.stats.keyframes, 2u);
  EXPECT_LT(run.stats.keyframes, 100u);
}
