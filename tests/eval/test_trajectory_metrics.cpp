// ATE / RPE against hand-built trajectories with known answers (METHODS.md D).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "semap/core/error.hpp"
#include "semap/eval/trajectory_metrics.hpp"

namespace semap {
namespace {

// A smooth 3D path with rotation, 30 Hz, `n` poses.
Trajectory make_trajectory(size_t n, double t0 = 1000.0, double rate_hz = 30.0) {
  Trajectory traj;
  for (size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / rate_hz;
    StampedPose p;
    p.timestamp = t0 + t;
    const Eigen::Vector3d pos(std::cos(0.4 * t) * 2.0, std::sin(0.3 * t) * 1.5, 0.2 * t);
    const Eigen::Quaterniond q = Eigen::AngleAxisd(0.3 * t, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(0.1 * std::sin(t), Eigen::Vector3d::UnitX());
    p.T_world_camera = pose_from_tq(pos, q);
    traj.push_back(p);
  }
  return traj;
}

Pose arbitrary_rigid() {
  Pose T = Pose::Identity();
  T.linear() = (Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.3, -0.5, 0.8).normalized())).toRotationMatrix();
  T.translation() = Eigen::Vector3d(4.0, -2.5, 7.0);
  return T;
}

TEST(Ate, SelfAfterRigidTransformIsZero) {
  const Trajectory gt = make_trajectory(300);
  Trajectory est = gt;
  const Pose T = arbitrary_rigid();
  for (auto& p : est) p.T_world_camera = T * p.T_world_camera;
  const AteResult ate = compute_ate(gt, est);
  EXPECT_EQ(ate.matched, gt.size());
  EXPECT_LT(ate.rmse, 1e-9);
  EXPECT_LT(ate.max, 1e-9);
  // The alignment recovers the inverse of the applied transform.
  EXPECT_TRUE((ate.T_gt_est * T).isApprox(Pose::Identity(), 1e-9));
}

TEST(Ate, AlternatingOffsetEqualsOffset) {
  // +/- d along a fixed axis on alternating frames: zero mean, so no rigid alignment can
  // absorb it; every error is exactly d after alignment (the optimum stays the identity).
  const Trajectory gt = make_trajectory(400);
  Trajectory est = gt;
  const double d = 0.05;
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -1).normalized();
  for (size_t i = 0; i < est.size(); ++i)
    est[i].T_world_camera.translation() += (i % 2 == 0 ? d : -d) * axis;
  const AteResult ate = compute_ate(gt, est);
  EXPECT_NEAR(ate.rmse, d, 2e-3);
  EXPECT_NEAR(ate.mean, d, 2e-3);
  EXPECT_NEAR(ate.median, d, 2e-3);
  // And the same with an extra rigid transform on top.
  for (auto& p : est) p.T_world_camera = arbitrary_rigid() * p.T_world_camera;
  EXPECT_NEAR(compute_ate(gt, est).rmse, d, 2e-3);
}

TEST(Ate, ConstantOffsetIsAbsorbedByAlignment) {
  const Trajectory gt = make_trajectory(100);
  Trajectory est = gt;
  for (auto& p : est) p.T_world_camera.translation() += Eigen::Vector3d(0.3, 0.1, -0.2);
  EXPECT_LT(compute_ate(gt, est).rmse, 1e-9);
}

TEST(Ate, UsesTimestampAssociation) {
  // est at jittered timestamps (< 10 ms), missing every 7th frame, and extra poses far away
  // in time that must not associate.
  const Trajectory gt = make_trajectory(300);
  Trajectory est;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.009, 0.009);
  for (size_t i = 0; i < gt.size(); ++i) {
    if (i % 7 == 3) continue;
    StampedPose p = gt[i];
    p.timestamp += jitter(rng);
    est.push_back(p);
  }
  StampedPose stray = gt.back();
  stray.timestamp += 5.0;
  stray.T_world_camera.translation() += Eigen::Vector3d(10, 10, 10);
  est.push_back(stray);
  const AteResult ate = compute_ate(gt, est);
  EXPECT_EQ(ate.matched, gt.size() - (gt.size() + 3) / 7);
  EXPECT_LT(ate.rmse, 1e-9);
  // Shifting est by 100 s breaks the association entirely.
  for (auto& p : est) p.timestamp += 100.0;
  EXPECT_THROW(compute_ate(gt, est), Error);
}

TEST(Rpe, IdenticalIsZero) {
  const Trajectory gt = make_trajectory(300);
  Trajectory est = gt;
  for (auto& p : est) p.T_world_camera = arbitrary_rigid() * p.T_world_camera;
  const RpeResult rpe = compute_rpe(gt, est);
  // 300 frames at 30 Hz: pairs start at frames 0..269.
  EXPECT_EQ(rpe.pairs, 270u);
  EXPECT_LT(rpe.trans_rmse_m_per_s, 1e-9);
  EXPECT_LT(rpe.rot_rmse_deg_per_s, 1e-9);
}

TEST(Rpe, ConstantTranslationDriftRate) {
  const Trajectory gt = make_trajectory(300);
  Trajectory est = gt;
  const Eigen::Vector3d velocity(0.03, -0.04, 0.0);  // 5 cm/s drift in the world frame
  for (auto& p : est) {
    Pose drift = Pose::Identity();
    drift.translation() = velocity * (p.timestamp - gt.front().timestamp);
    p.T_world_camera = drift * p.T_world_camera;
  }
  const RpeResult rpe = compute_rpe(gt, est);
  EXPECT_GT(rpe.pairs, 200u);
  EXPECT_NEAR(rpe.trans_rmse_m_per_s, 0.05, 1e-9);
  EXPECT_LT(rpe.rot_rmse_deg_per_s, 1e-9);
}

TEST(Rpe, ConstantRotationDriftRate) {
  const Trajectory gt = make_trajectory(300);
  Trajectory est = gt;
  const double deg_per_s = 2.0;
  for (auto& p : est) {
    const double angle = deg_per_s * M_PI / 180.0 * (p.timestamp - gt.front().timestamp);
    p.T_world_camera = Pose(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY())) * p.T_world_camera;
  }
  const RpeResult rpe = compute_rpe(gt, est);
  EXPECT_NEAR(rpe.rot_rmse_deg_per_s, deg_per_s, 1e-6);
  EXPECT_GT(rpe.trans_rmse_m_per_s, 0.0);  // rotation about the world origin moves the camera
}

TEST(Rpe, ShorterThanDeltaHasNoPairs) {
  const Trajectory gt = make_trajectory(20);  // 0.63 s
  EXPECT_EQ(compute_rpe(gt, gt).pairs, 0u);
}

}  // namespace
}  // namespace semap
