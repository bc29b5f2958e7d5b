// Issue 16: tracking on subsampled shared sequences (wide baselines, fast motion) and across a
// 20-frame sensor dropout. The sequences are written at test time by tests/sequence_slices
// (TUM-layout folders of links in a temp dir). Thresholds are the targets.
#include <gtest/gtest.h>

#include "semap/eval/trajectory_metrics.hpp"
#include "sequence_slices.hpp"
#include "test_support.hpp"
#include "tracking/tracking_test_util.hpp"

using namespace semap;

namespace {

test::TrackingRun run_slice(const std::filesystem::path& source, const test::SliceSpec& spec) {
  test::TempDir tmp("semap_slice");
  const test::SequenceSlice slice = test::write_sequence_slice(source, spec, tmp / "slice");
  TrackingConfig config;
  config.background_loop_closure = false;  // deterministic
  std::cout << "[tracking] slice " << source.filename().string() << " " << test::describe(spec) << std::endl;
  return test::run_tracker_on(slice.dir, slice.size(), config);
}

test::SliceSpec every(size_t k, size_t last = std::numeric_limits<size_t>::max()) {
  test::SliceSpec spec;
  spec.step = k;
  spec.last = last;
  return spec;
}

double rotation_deg(const Pose& a, const Pose& b) { return rotation_angle(a.inverse() * b) * 180.0 / M_PI; }

}  // namespace

TEST(TrackingSlices, SliceHelperWritesEveryKthFrameWithGroundTruth) {
  SEMAP_REQUIRE_DATA(dir, "7scenes_redkitchen");
  test::TempDir tmp("semap_slice");
  test::SliceSpec spec = every(10, 99);
  spec.blank_begin = 3;
  spec.blank_end = 5;
  const test::SequenceSlice slice = test::write_sequence_slice(dir, spec, tmp / "slice");
  ASSERT_EQ(slice.size(), 10u);
  const auto source = open_dataset(dir);
  const auto reader = open_dataset(slice.dir);
  ASSERT_EQ(reader->size(), 10u);
  EXPECT_EQ(reader->format(), "tum");
  EXPECT_EQ(reader->camera().depth, source->camera().depth);
  for (size_t i = 0; i < reader->size(); ++i) {
    const Frame f = reader->load(i);
    const Frame g = source->load(10 * i);
    ASSERT_TRUE(f.gt_T_world_camera && g.gt_T_world_camera);
    EXPECT_LT((f.gt_T_world_camera->translation() - g.gt_T_world_camera->translation()).norm(), 1e-6) << i;
    const bool blank = i == 3 || i == 4;
    EXPECT_EQ(slice.blank[i], blank);
    EXPECT_EQ(cv::countNonZero(f.depth), blank ? 0 : cv::countNonZero(g.depth)) << i;
  }
  // Reversed: increasing timestamps, frames in the opposite order.
  test::SliceSpec reversed = every(10, 99);
  reversed.reverse = true;
  const auto back = open_dataset(test::write_sequence_slice(dir, reversed, tmp / "back").dir);
  ASSERT_EQ(back->size(), 10u);
  EXPECT_LT((back->load(0).gt_T_world_camera->translation() - source->load(90).gt_T_world_camera->translation()).norm(), 1e-6);
}

TEST(TrackingSlices, RedkitchenEvery10thFrame) {
  SEMAP_REQUIRE_DATA(dir, "7scenes_redkitchen");
  const auto run = run_slice(dir, every(10));
  EXPECT_LE(run.ate_rmse, 0.06);
  EXPECT_LE(run.lost, 2u);
}

TEST(TrackingSlices, RedkitchenEvery5thFrame) {
  SEMAP_REQUIRE_DATA(dir, "7scenes_redkitchen");
  const auto run = run_slice(dir, every(5));
  EXPECT_LE(run.ate_rmse, 0.04);
  EXPECT_LE(run.lost, 2u);
}

TEST(TrackingSlices, TumFr1RpyEvery3rdFrame) {
  SEMAP_REQUIRE_DATA(dir, "tum_fr1_rpy");
  const auto run = run_slice(dir, every(3));
  EXPECT_LE(run.ate_rmse, 0.03);
  EXPECT_LE(run.lost, 2u);
}

// Issue 42: keyframe-rate slices, frames at least 25 cm or 20 deg apart by the ground truth (a
// robot recording at 1-2 Hz). A frame may be lost, but a pose the tracker verified must be
// right: each verified frame's motion from the previous verified frame within 10 cm / 5 deg of
// the ground truth's (a wrong registration is off by tens of centimetres, issue 42).
struct KeyframeRateRun {
  size_t frames = 0, lost = 0, wrong_verified = 0;
  double ate_rmse_m = 0;
};

KeyframeRateRun run_keyframe_rate(const std::filesystem::path& source) {
  test::TempDir tmp("semap_kf_slice");
  test::SliceSpec spec;
  spec.frames = test::frames_by_motion(source, 0.25, 20.0);
  const test::SequenceSlice slice = test::write_sequence_slice(source, spec, tmp / "slice");
  auto reader = open_dataset(slice.dir);
  TrackingConfig config;
  config.background_loop_closure = false;
  Tracker tracker(config, reader->camera());
  KeyframeRateRun run;
  std::vector<Pose> gt;
  std::vector<TrackResult> results;
  for (size_t i = 0; i < reader->size(); ++i) {
    const Frame f = reader->load(i);
    gt.push_back(*f.gt_T_world_camera);
    results.push_back(tracker.track(f));
  }
  run.frames = results.size();
  size_t last = 0;  // last verified frame
  for (size_t i = 1; i < results.size(); ++i) {
    if (!results[i].pose_verified()) {
      ++run.lost;
      continue;
    }
    const Pose truth = gt[last].inverse() * gt[i];
    const Pose est = results[last].T_world_camera.inverse() * results[i].T_world_camera;
    last = i;
    const double dt = (est.translation() - truth.translation()).norm(), dr = rotation_deg(est, truth);
    run.wrong_verified += dt > 0.10 || dr > 5.0;
    if (dt > 0.10 || dr > 5.0)
      std::cout << "[tracking] verified frame " << i << " is " << dt * 100 << " cm / " << dr << " deg off" << std::endl;
  }
  Trajectory truth_traj;
  for (size_t i = 0; i < gt.size(); ++i) truth_traj.push_back({results[i].timestamp, gt[i]});
  run.ate_rmse_m = compute_ate(truth_traj, tracker.finish()).rmse;
  std::cout << "[tracking] keyframe-rate slice " << source.filename().string() << ": " << run.frames << " frames, lost "
            << run.lost << ", wrong verified " << run.wrong_verified << ", ATE " << run.ate_rmse_m * 100 << " cm" << std::endl;
  return run;
}

// fr1_rpy at keyframe rate: 16 frames, 4 lost; ATE 3.10 cm with the lost frames' poses
// interpolated between their verified neighbours (lost_frame_poses.hpp), 3.28 cm held.
TEST(TrackingSlices, TumFr1RpyKeyframeRate) {
  SEMAP_REQUIRE_DATA(dir, "tum_fr1_rpy");
  const KeyframeRateRun run = run_keyframe_rate(dir);
  ASSERT_GE(run.frames, 10u);
  EXPECT_EQ(run.wrong_verified, 0u);
  EXPECT_LE(run.ate_rmse_m, 0.10);  // the keyframe-rate target
  EXPECT_LE(run.lost, run.frames / 3);
}

// redkitchen at keyframe rate: 15 frames, 25 cm and up to 20 deg apart (the overlap of
// consecutive ones 0.47-0.89 by the ground truth). With the per-frame 700 ORB keypoints alone
// the wide baselines shared too few matches: 11 of 15 lost, ATE 56.7 cm; with the dense
// wide-baseline set (tracking.orb_wide_features) measured 2 lost, ATE 11.4 cm, none wrong (the
// two lost frames are the last two: no verified frame after them to interpolate towards).
TEST(TrackingSlices, RedkitchenKeyframeRate) {
  SEMAP_REQUIRE_DATA(dir, "7scenes_redkitchen");
  const KeyframeRateRun run = run_keyframe_rate(dir);
  ASSERT_GE(run.frames, 10u);
  EXPECT_EQ(run.wrong_verified, 0u);
  EXPECT_LE(run.lost, run.frames / 4);
  EXPECT_LE(run.ate_rmse_m, 0.15);
}

// 20 frames of all-zero depth and black colour mid-sequence: every one is lost (never a pose
// that failed its checks), and the first frame after the gap is relocalised within 5 cm / 3 deg
// of the ground truth, measured relative to the last frame before the gap (drift before the
// gap is not what this checks).
void check_gap(const std::filesystem::path& source, size_t frames, size_t gap_begin) {
  test::TempDir tmp("semap_gap");
  test::SliceSpec spec = every(1, frames - 1);
  spec.blank_begin = gap_begin;
  spec.blank_end = gap_begin + 20;
  const test::SequenceSlice slice = test::write_sequence_slice(source, spec, tmp / "gap");
  auto reader = open_dataset(slice.dir);
  TrackingConfig config;
  config.background_loop_closure = false;
  Tracker tracker(config, reader->camera());
  std::vector<TrackResult> results;
  std::vector<Pose> gt;
  for (size_t i = 0; i < reader->size(); ++i) {
    const Frame f = reader->load(i);
    gt.push_back(*f.gt_T_world_camera);
    results.push_back(tracker.track(f));
  }
  for (size_t i = spec.blank_begin; i < spec.blank_end; ++i) {
    EXPECT_EQ(results[i].status, TrackingStatus::lost) << "blank frame " << i;
    EXPECT_FALSE(results[i].pose_verified()) << "blank frame " << i;
  }
  const size_t before = gap_begin - 1, after = spec.blank_end;
  ASSERT_TRUE(results[before].pose_verified());
  EXPECT_TRUE(results[after].pose_verified()) << "not relocalised right after the gap";
  size_t lost_after = 0;
  for (size_t i = after; i < results.size(); ++i) lost_after += !results[i].pose_verified();
  EXPECT_LE(lost_after, 2u);
  const Pose est = results[before].T_world_camera.inverse() * results[after].T_world_camera;
  const Pose truth = gt[before].inverse() * gt[after];
  const double dt = (est.translation() - truth.translation()).norm(), dr = rotation_deg(est, truth);
  std::cout << "[tracking] gap " << source.filename().string() << " frames " << spec.blank_begin << ".."
            << spec.blank_end - 1 << ": motion across the gap " << truth.translation().norm() * 100 << " cm "
            << rotation_deg(Pose::Identity(), truth) << " deg, error after it " << dt * 100 << " cm " << dr
            << " deg (" << to_string(results[after].status) << ")" << std::endl;
  EXPECT_LE(dt, 0.05);
  EXPECT_LE(dr, 3.0);
  // The trajectory's poses of the blank frames, interpolated between the frames around the gap
  // (lost_frame_poses.hpp), against the held pose: error in the motion from the frame before.
  const Trajectory trajectory = tracker.finish();
  ASSERT_EQ(trajectory.size(), results.size());
  double held_m = 0, held_deg = 0, filled_m = 0, filled_deg = 0;
  for (size_t i = spec.blank_begin; i < spec.blank_end; ++i) {
    const Pose motion = gt[before].inverse() * gt[i];
    const Pose filled = trajectory[before].T_world_camera.inverse() * trajectory[i].T_world_camera;
    held_m += motion.translation().squaredNorm();
    held_deg += std::pow(rotation_deg(Pose::Identity(), motion), 2);
    filled_m += (filled.translation() - motion.translation()).squaredNorm();
    filled_deg += std::pow(rotation_deg(filled, motion), 2);
  }
  const double n = double(spec.blank_end - spec.blank_begin);
  std::cout << "[tracking] blank frames' error in the motion from the frame before the gap: held "
            << std::sqrt(held_m / n) * 100 << " cm " << std::sqrt(held_deg / n) << " deg, interpolated "
            << std::sqrt(filled_m / n) * 100 << " cm " << std::sqrt(filled_deg / n) << " deg" << std::endl;
  EXPECT_LT(filled_m + std::pow(0.01, 2) * filled_deg, held_m + std::pow(0.01, 2) * held_deg)
      << "1 deg weighed as 1 cm";
}

TEST(TrackingSlices, TumFr1RpyRelocalisesAfter20BlankFrames) {
  SEMAP_REQUIRE_DATA(dir, "tum_fr1_rpy");
  check_gap(dir, 200, 100);
}

TEST(TrackingSlices, RedkitchenRelocalisesAfter20BlankFrames) {
  SEMAP_REQUIRE_DATA(dir, "7scenes_redkitchen");
  check_gap(dir, 200, 100);
}
