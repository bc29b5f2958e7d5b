// Frame-to-model tracking (issue 42, METHODS.md A2; CI heavy subset): with
// tracking.model_keyframes the keyframes' ICP targets come from the fused TSDF (the pipeline
// hands the tracker a read-only model view). 7-Scenes redkitchen, 500 consecutive frames,
// pipeline.threads 1 (deterministic): measured 2.83 cm ATE against 3.17 cm with the keyframes'
// own depth (the issue's target: <= 3.0 cm). On TUM fr1_rpy it measured worse (1.87 against
// 1.46 cm), so the option is off by default; this checks the model path end to end.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/progress.hpp"
#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/dataset.hpp"
#include "semap/io/trajectory_io.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

TEST(FrameToModel, RedkitchenKeyframesFromTheFusedModelMeetTheIssueTarget) {
  SEMAP_REQUIRE_DATA(kitchen, "7scenes_redkitchen");
  Progress::set_mode(-1);
  test::TempDir tmp("semap_frame_to_model");
  RunOptions options;
  options.segmenter = "none";
  options.dataset = kitchen;
  options.out_dir = tmp / "out";
  options.show_progress = false;
  options.evaluate = false;
  SemapConfig config;
  config.pipeline.threads = 1;
  config.tracking.model_keyframes = true;
  run_pipeline(options, config);
  const Trajectory est = read_tum_trajectory(tmp / "out" / "trajectory.txt");
  const Trajectory gt = open_dataset(kitchen)->ground_truth();
  const double ate = compute_ate(gt, est).rmse;
  const RpeResult rpe = compute_rpe(gt, est);
  std::printf("[frame-to-model] redkitchen ATE %.2f cm, RPE %.2f cm/s %.3f deg/s\n", ate * 100,
              rpe.trans_rmse_m_per_s * 100, rpe.rot_rmse_deg_per_s);
  EXPECT_EQ(est.size(), 500u);
  EXPECT_LE(ate, 0.030);  // the issue-42 target; the keyframes' own depth gives 3.17 cm
}

}  // namespace
}  // namespace semap
