// Longer tracking runs (LABELS heavy), the issue-4 figures: TUM fr1_rpy 200 frames (ATE <= 2.5 cm
// and lower than Open3D's hybrid RGB-D odometry on the same frames), 7-Scenes redkitchen 500
// frames (ATE <= 4 cm) and a synthetic closed loop with depth noise (ATE <= 1 cm, loop closure
// lowers ATE against odometry alone).
// Measured (2 shared cores, deterministic): TUM 2.0 cm (Open3D 6.4 cm), redkitchen 3.45 cm,
// synthetic 0.20 cm with loop closure vs 0.85 cm odometry only.
#include <gtest/gtest.h>

#include "bench/open3d_odometry.hpp"
#include "semap/eval/trajectory_metrics.hpp"

#include "synth/synth_config.hpp"
#include "test_support.hpp"
#include "tracking/tracking_test_util.hpp"

using namespace semap;

TEST(TrackingHeavy, TumFr1Rpy200IssueTarget) {
  SEMAP_REQUIRE_DATA(dir, "tum_fr1_rpy");
  TrackingConfig config;
  config.background_loop_closure = false;
  const auto run = test::run_tracker_on(dir, 200, config);
  EXPECT_LE(run.ate_rmse, 0.025);
#ifdef SEMAP_HAVE_OPEN3D
  // Open3D's hybrid odometry (frame to frame) on the same 200 frames: ours must be lower.
  auto reader = open_dataset(dir);
  std::vector<Frame> frames;
  Trajectory gt;
  for (size_t i = 0; i < std::min<size_t>(200, reader->size()); ++i) {
    frames.push_back(reader->load(i));
    if (frames.back().gt_T_world_camera) gt.push_back({frames.back().timestamp, *frames.back().gt_T_world_camera});
  }
  const auto open3d = baseline::run_open3d_odometry(frames, reader->camera());
  const double open3d_ate = compute_ate(gt, open3d.trajectory).rmse;
  std::cout << "[tracking] tum_fr1_rpy ATE ours " << run.ate_rmse * 100 << " cm, Open3D hybrid "
            << open3d_ate * 100 << " cm" << std::endl;
  EXPECT_LT(run.ate_rmse, open3d_ate);
#else
  std::cout << "[tracking] Open3D not found at build time: comparison skipped" << std::endl;
#endif
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
  EXPECT_GE(with_loops.stats.loop_edges, 1u) << "the loop must close with a verified loop edge";
  EXPECT_LT(with_loops.ate_rmse, 0.9 * odometry_only.ate_rmse);
}
