// TUM fr1_rpy, first 200 frames, tracked without ground truth (issue 4: ATE RMSE <= 2.5 cm).
#include <gtest/gtest.h>

#include "test_support.hpp"
#include "tracking/tracking_test_util.hpp"

using namespace semap;

TEST(TrackingDatasets, TumFr1Rpy200) {
  SEMAP_REQUIRE_DATA(dir, "tum_fr1_rpy");
  TrackingConfig config;
  config.background_loop_closure = false;  // deterministic
  const auto run = test::run_tracker_on(dir, 200, config);
  EXPECT_LE(run.ate_rmse, 0.025);
  EXPECT_GT(run.rpe_trans, 0.0);
  EXPECT_LE(run.lost, 10u);
}
