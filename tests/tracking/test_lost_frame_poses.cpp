// Issue 42: the trajectory's poses of lost frames (src/tracking/lost_frame_poses.cpp).
#include <gtest/gtest.h>

#include "semap/core/error.hpp"
#include "tracking/lost_frame_poses.hpp"

namespace semap {
namespace {

Pose at(double x, double yaw_rad) {
  Pose p = Pose::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.translation() = Eigen::Vector3d(x, 0, 0);
  return p;
}

/// Verified frames at t = 0, 1, 4 (x = t, yaw = t/10); lost frames at 2 and 3 held at t = 1's
/// pose, and one lost frame after the last verified one at t = 5.
const std::vector<bool> kVerified = {true, true, false, false, true, false};
Trajectory held_samples() {
  Trajectory s;
  for (double t : {0.0, 1.0, 2.0, 3.0, 4.0, 5.0}) {
    const bool verified = kVerified[size_t(t)];
    s.push_back({t, verified ? at(t, t / 10) : at(t >= 4 ? 4 : 1, (t >= 4 ? 4 : 1) / 10.0)});
  }
  return s;
}

TEST(LostFramePoses, LostFramesBetweenVerifiedOnesAreInterpolatedByTime) {
  Trajectory s = held_samples();
  fill_lost_poses(s, kVerified, 5.0);
  for (size_t i : {2u, 3u}) {
    const double t = s[i].timestamp;
    EXPECT_NEAR((s[i].T_world_camera.translation() - Eigen::Vector3d(t, 0, 0)).norm(), 0.0, 1e-12) << t;
    EXPECT_NEAR(rotation_angle(s[i].T_world_camera), t / 10, 1e-9) << t;
  }
  // Verified frames untouched; the lost frame after the last verified one stays held.
  EXPECT_TRUE(s[1].T_world_camera.isApprox(at(1, 0.1)));
  EXPECT_TRUE(s[4].T_world_camera.isApprox(at(4, 0.4)));
  EXPECT_TRUE(s[5].T_world_camera.isApprox(at(4, 0.4)));
}

TEST(LostFramePoses, AGapLongerThanTheLimitOrALimitOfZeroKeepsTheHeldPoses) {
  for (double max_gap_s : {2.9, 0.0}) {  // the verified frames around the gap are 3 s apart
    Trajectory s = held_samples();
    fill_lost_poses(s, kVerified, max_gap_s);
    for (size_t i = 0; i < s.size(); ++i)
      EXPECT_TRUE(s[i].T_world_camera.isApprox(held_samples()[i].T_world_camera)) << max_gap_s << " " << i;
  }
}

TEST(LostFramePoses, LostFramesBeforeTheFirstVerifiedOneStayHeldAndFlagsMustMatch) {
  Trajectory s = {{0.0, at(7, 0)}, {1.0, at(1, 0)}, {2.0, at(2, 0)}};
  fill_lost_poses(s, {false, true, true}, 5.0);
  EXPECT_TRUE(s[0].T_world_camera.isApprox(at(7, 0)));
  EXPECT_THROW(fill_lost_poses(s, {true, true}, 5.0), Error);
}

TEST(LostFramePoses, EachGapIsInterpolatedBetweenItsOwnVerifiedFrames) {
  // Verified at t = 0, 10, 20 (x = 0, 1, 5); two gaps of 999 lost frames held at the last pose.
  Trajectory s;
  std::vector<bool> verified;
  for (int k = 0; k <= 2000; ++k) {
    verified.push_back(k % 1000 == 0);
    const double held_x = k < 1000 ? 0 : k < 2000 ? 1 : 5;
    s.push_back({k / 100.0, at(verified.back() ? held_x : (k < 1000 ? 0 : 1), 0)});
  }
  fill_lost_poses(s, verified, 10.0);
  EXPECT_NEAR(s[500].T_world_camera.translation().x(), 0.5, 1e-9);
  EXPECT_NEAR(s[1500].T_world_camera.translation().x(), 3.0, 1e-9);
  EXPECT_NEAR(s[1999].T_world_camera.translation().x(), 1.0 + 4.0 * 0.999, 1e-9);
}

}  // namespace
}  // namespace semap
