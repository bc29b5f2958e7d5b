// Real tracking with the loop-closure worker thread (the product default), for the
// ThreadSanitizer step of scripts/ci-sanitize.sh (issue 16): a short real sequence, loop
// candidates made easy to reach so the worker verifies and optimises while the main thread
// tracks and reads poses. Keep it short: it runs under TSan (< 60 s there).
#include <gtest/gtest.h>

#include "sequence_slices.hpp"
#include "test_support.hpp"
#include "tracking/tracking_test_util.hpp"

using namespace semap;

TEST(TrackingThreads, LoopClosureWorkerWithRealTracking) {
  SEMAP_REQUIRE_DATA(dir, "7scenes_redkitchen");
  // 60 frames, every 3rd of the first 180, then back again: the camera revisits its start.
  test::TempDir tmp("semap_threads");
  test::SliceSpec forward;
  forward.last = 89;
  forward.step = 3;
  const auto slice = test::write_sequence_slice(dir, forward, tmp / "slice");
  auto reader = open_dataset(slice.dir);
  TrackingConfig config;
  config.background_loop_closure = true;
  config.loop_min_keyframe_gap = 2;
  config.loop_min_similarity = 0.2;
  Tracker tracker(config, reader->camera());
  Trajectory gt;
  size_t lost = 0;
  for (size_t pass = 0; pass < 2; ++pass) {
    for (size_t j = 0; j < reader->size(); ++j) {
      const size_t i = pass == 0 ? j : reader->size() - 1 - j;
      Frame f = reader->load(i);
      f.timestamp += pass * 100.0;  // the return pass is later in time
      f.index = pass * reader->size() + j;
      gt.push_back({f.timestamp, *f.gt_T_world_camera});
      const TrackResult r = tracker.track(f);
      lost += !r.pose_verified();
      // The main thread reads what the worker writes.
      EXPECT_EQ(tracker.trajectory().size(), f.index + 1);
      EXPECT_FALSE(tracker.keyframes().empty());
    }
  }
  const Trajectory est = tracker.finish();
  ASSERT_EQ(est.size(), 2 * reader->size());
  const double ate = compute_ate(gt, est).rmse;
  const TrackerStats s = tracker.stats();
  std::cout << "[tracking] threads: ATE " << ate * 100 << " cm, keyframes " << s.keyframes << " loops "
            << s.loop_edges << " optimisations " << s.optimisations << " lost " << lost << std::endl;
  EXPECT_LE(ate, 0.05);
  EXPECT_LE(lost, 3u);
  EXPECT_GE(s.optimisations, 1u);  // the worker (or finish) optimised the graph
}
