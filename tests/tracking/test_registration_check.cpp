// Issue 42: the checks a registration must pass before it is trusted (tracking/registration_check),
// on synthetic cases with known answers: each check fires where it must (a pose 30 cm off, a
// plane-only scene, a repetitive pattern, inliers on one patch) and not on the true pose. The
// thresholds are the tracking defaults (VerificationParams), not values chosen for these scenes.
#include <gtest/gtest.h>

#include <random>

#include "tracking/registration.hpp"
#include "tracking/registration_check.hpp"
#include "tracking/synthetic_room.hpp"

using namespace semap;
using semap::test::make_pose;
using semap::test::render_room;

namespace {
/// Kinect-like axial noise (the sensor model of VerificationParams) on a rendered depth.
cv::Mat add_depth_noise(const cv::Mat& depth, const VerificationParams& vp, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  cv::Mat out = depth.clone();
  for (int v = 0; v < out.rows; ++v)
    for (int u = 0; u < out.cols; ++u) {
      float& z = out.at<float>(v, u);
      if (z > 0) z = float(z + depth_noise_sigma(z, vp) * n01(rng));
    }
  return out;
}

std::vector<DepthLevel> pyramid(const cv::Mat& depth, const PinholeIntrinsics& k) {
  return build_depth_pyramid(depth, k, 3, 0.2, 8.0, true);
}

/// A wall 2 m in front of the camera, nothing else.
cv::Mat render_wall(const PinholeIntrinsics& k) { return cv::Mat(k.height, k.width, CV_32FC1, cv::Scalar(2.0f)); }
}  // namespace

TEST(RegistrationCheck, DenseResidualPassesTruePoseAndRejectsPoses30cmOffAlongTheView) {
  const PinholeIntrinsics k;  // 640x480, f = 525
  const VerificationParams vp;
  const Pose T_world_ref = make_pose(0, 0, 0, 0, 0, 0);
  const Pose T_world_frame = make_pose(0.03, -0.05, 0.02, 0.08, -0.03, 0.06);
  const auto ref = pyramid(add_depth_noise(render_room(k, T_world_ref), vp, 1), k);
  const auto frame = pyramid(add_depth_noise(render_room(k, T_world_frame), vp, 2), k);
  const Pose truth = T_world_ref.inverse() * T_world_frame;
  const size_t level = size_t(vp.residual_level);
  const DenseResidual good = dense_depth_residual(frame[level], ref[level], truth, vp);
  std::cout << "[check] true pose: consistent " << good.consistent_fraction() << " overlap " << good.overlap_fraction()
            << std::endl;
  EXPECT_GE(good.consistent_fraction(), 0.95);
  EXPECT_GE(good.consistent_fraction(), vp.min_consistent_fraction);
  EXPECT_GE(good.agreeing_share(), 0.9);
  EXPECT_GT(good.overlap_fraction(), 0.8);
  // 30 cm off, either way: along the view the reference sees through the frame (or the frame
  // hides behind it); sideways, the room's walls slide along themselves and only the sphere,
  // the block and the side walls disagree (depth alone: lower agreement, not below the bound).
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {-1.0, 1.0}) {
      Pose offset = Pose::Identity();
      offset.translation()[axis] = 0.3 * sign;
      const DenseResidual bad = dense_depth_residual(frame[level], ref[level], truth * offset, vp);
      std::cout << "[check] offset " << 0.3 * sign << " m along axis " << axis << ": consistent "
                << bad.consistent_fraction() << " agreeing share " << bad.agreeing_share() << " (" << bad.agreeing << " agree, " << bad.violating << " violate)"
                << std::endl;
      if (axis == 2)
        EXPECT_TRUE(bad.consistent_fraction() < vp.min_consistent_fraction || bad.agreeing_share() < vp.min_agreeing_share)
            << "sign " << sign;
      else EXPECT_LT(bad.consistent_fraction(), good.consistent_fraction() - 0.1) << "axis " << axis << " sign " << sign;
    }
}

// Conditioning at the coarsest level (where the tracker evaluates it), with Kinect-like noise.
TEST(RegistrationCheck, PlaneOnlySceneIsUnderConstrainedRoomIsNot) {
  const PinholeIntrinsics k;
  const VerificationParams vp;
  auto eigenvalue = [&](const cv::Mat& depth) {
    return scaled_min_information_eigenvalue(point_to_plane_information(pyramid(add_depth_noise(depth, vp, 3), k).back()));
  };
  const double wall = eigenvalue(render_wall(k));
  const double room = eigenvalue(render_room(k, Pose::Identity()));
  const double moved = eigenvalue(render_room(k, make_pose(0.1, -0.2, 0.05, 0.3, 0.1, -0.2)));
  std::cout << "[check] smallest scaled information eigenvalue: wall " << wall << ", room " << room << ", room moved "
            << moved << " (threshold " << vp.min_information_eigenvalue << ")" << std::endl;
  EXPECT_LT(wall, vp.min_information_eigenvalue);
  EXPECT_GT(room, 2 * vp.min_information_eigenvalue);
  EXPECT_GT(moved, 2 * vp.min_information_eigenvalue);
  EXPECT_EQ(scaled_min_information_eigenvalue(Matrix6d::Zero()), 0.0);
}

// Two identical cabinet fronts 0.6 m apart: half of the feature matches go to the wrong copy.
// RANSAC finds one of the two models; the other, with nearly as many votes, makes it ambiguous.
// With the same number of plain outliers instead, nothing comparable competes.
TEST(RegistrationCheck, RepetitivePatternGivesAmbiguousSecondModel) {
  const VerificationParams vp;
  RansacParams params;
  params.seed = 5;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.25, 0.25);
  std::normal_distribution<double> noise(0.0, 0.004);
  const Pose truth = make_pose(0.05, 0.1, -0.03, 0.1, 0.02, -0.05);
  const Eigen::Vector3d copy_offset(0.6, 0.0, 0.0);
  std::vector<Eigen::Vector3d> src, repetitive, outliers;
  for (int i = 0; i < 120; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), 2.0 + 0.2 * u(rng));
    const Eigen::Vector3d n(noise(rng), noise(rng), noise(rng));
    src.push_back(p);
    const bool wrong = i % 2 == 1;
    repetitive.push_back(truth * p + n + (wrong ? Eigen::Vector3d(truth.linear() * copy_offset) : Eigen::Vector3d::Zero()));
    outliers.push_back(wrong ? Eigen::Vector3d(4 * u(rng), 4 * u(rng), 2.0 + 4 * u(rng)) : Eigen::Vector3d(truth * p + n));
  }
  const RansacResult amb = ransac_rigid(src, repetitive, params);
  ASSERT_TRUE(amb.ok);
  const int amb_runner_up = ransac_runner_up(amb, src, repetitive, params.inlier_distance);
  const RansacResult clean = ransac_rigid(src, outliers, params);
  ASSERT_TRUE(clean.ok);
  const int clean_runner_up = ransac_runner_up(clean, src, outliers, params.inlier_distance);
  std::cout << "[check] repetitive: best " << amb.best_votes << " votes, runner-up " << amb_runner_up
            << "; outliers: best " << clean.best_votes << ", runner-up " << clean_runner_up << std::endl;
  EXPECT_GE(amb_runner_up, vp.ambiguity_vote_ratio * amb.best_votes);
  EXPECT_LT(clean_runner_up, vp.ambiguity_vote_ratio * clean.best_votes);
  // The clean case still finds the true model.
  EXPECT_LT((clean.T.translation() - truth.translation()).norm(), 0.02);
}

TEST(RegistrationCheck, InlierSpreadCountsOccupiedGridCells) {
  const VerificationParams vp;
  std::vector<cv::Point2f> patch, spread;
  for (int i = 0; i < 50; ++i) {
    patch.emplace_back(20.0f + float(i % 7), 30.0f + float(i / 7));  // one 7x8 px patch
    spread.emplace_back(32.0f + 64.0f * float(i % 10), 48.0f + 96.0f * float(i / 10));  // a 10 x 5 lattice
  }
  EXPECT_EQ(occupied_grid_cells(patch, 640, 480, vp.spread_grid), 1);
  EXPECT_LT(occupied_grid_cells(patch, 640, 480, vp.spread_grid), vp.spread_min_cells);
  EXPECT_EQ(occupied_grid_cells(spread, 640, 480, vp.spread_grid), vp.spread_grid * vp.spread_grid);
  EXPECT_EQ(occupied_grid_cells({{639.9f, 479.9f}, {-3.0f, 1000.0f}}, 640, 480, 4), 2);  // clamped at the borders
}
