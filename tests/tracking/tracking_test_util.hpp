#pragma once
// Runs the tracker over a dataset folder and measures ATE/RPE against its ground truth.
#include <filesystem>
#include <iostream>

#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/dataset.hpp"
#include "tracking/tracker.hpp"

namespace semap::test {

struct TrackingRun {
  double ate_rmse = 0, rpe_trans = 0, rpe_rot = 0;
  double ate_before_final = 0;
  size_t frames = 0, lost = 0;
  double ms_per_frame = 0;  ///< mean Tracker::track wall time (printed, never asserted: bench/ measures speed)
  TrackerStats stats;
};

inline TrackingRun run_tracker_on(const std::filesystem::path& dir, size_t max_frames, TrackingConfig config) {
  auto reader = open_dataset(dir);
  const size_t n = std::min(max_frames, reader->size());
  Tracker tracker(config, reader->camera());
  Trajectory gt;
  TrackingRun run;
  for (size_t i = 0; i < n; ++i) {
    const Frame frame = reader->load(i);
    if (frame.gt_T_world_camera) gt.push_back({frame.timestamp, *frame.gt_T_world_camera});
    const TrackResult r = tracker.track(frame);
    run.lost += r.status == TrackingStatus::lost;
    run.ms_per_frame += r.timings.total_ms / double(n);
  }
  if (gt.size() < 3) gt = reader->ground_truth();
  run.ate_before_final = compute_ate(gt, tracker.trajectory()).rmse;
  const Trajectory est = tracker.finish();
  EXPECT_EQ(est.size(), n) << "finish() must return every frame";
  run.frames = est.size();
  run.ate_rmse = compute_ate(gt, est).rmse;
  const RpeResult rpe = compute_rpe(gt, est);
  run.rpe_trans = rpe.trans_rmse_m_per_s;
  run.rpe_rot = rpe.rot_rmse_deg_per_s;
  run.stats = tracker.stats();
  std::cout << "[tracking] " << dir.filename().string() << " frames=" << n << " ATE=" << run.ate_rmse * 100
            << " cm (before final pass " << run.ate_before_final * 100 << " cm) RPE=" << run.rpe_trans * 100
            << " cm/s " << run.rpe_rot << " deg/s keyframes=" << run.stats.keyframes
            << " reuses=" << run.stats.keyframe_reuses << " loops=" << run.stats.loop_edges << " local=" << run.stats.local_edges
            << " lost=" << run.lost << " ms/frame=" << run.ms_per_frame << std::endl;
  return run;
}

}  // namespace semap::test
