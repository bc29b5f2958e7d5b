// Unit tests of the tracking building blocks (METHODS.md A1-A4) on synthetic data with known
// answers.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <opencv2/imgproc.hpp>
#include <iostream>

#include "semap/core/error.hpp"
#include "tracking/depth_repair.hpp"
#include "tracking/ferns.hpp"
#include "tracking/pose_graph.hpp"
#include "tracking/registration.hpp"
#include "tracking/tracker.hpp"
#include "tracking/synthetic_room.hpp"

using namespace semap;
using semap::test::make_pose;
using semap::test::render_room;

namespace {
/// ICP run to its noise floor on the noise-free synthetic renders (the tracker's defaults stop
/// earlier, at the Kinect noise floor).
IcpParams precise_icp() {
  IcpParams p;
  p.stride = 2;
  p.min_stride = 1;
  p.convergence_update = 1e-5;
  p.convergence_level_scale = 1.0;
  p.photometric_weight = 0.0;
  return p;
}
double translation_error(const Pose& a, const Pose& b) { return (a.translation() - b.translation()).norm(); }
double rotation_error(const Pose& a, const Pose& b) { return rotation_angle(a.inverse() * b); }

}  // namespace

TEST(RigidFit, RecoversExactTransform) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  const Pose truth = make_pose(0.3, -0.2, 0.5, 0.4, -0.1, 0.25);
  std::vector<Eigen::Vector3d> src, dst;
  for (int i = 0; i < 20; ++i) {
    src.emplace_back(u(rng), u(rng), 2 + u(rng));
    dst.push_back(truth * src.back());
  }
  bool ok = false;
  const Pose fit = fit_rigid(src, dst, &ok);
  ASSERT_TRUE(ok);
  EXPECT_LT(translation_error(fit, truth), 1e-9);
  EXPECT_LT(rotation_error(fit, truth), 1e-9);
  // Collinear points cannot define a rotation.
  std::vector<Eigen::Vector3d> line = {{0, 0, 1}, {0, 0, 2}, {0, 0, 3}};
  fit_rigid(line, line, &ok);
  EXPECT_FALSE(ok);
}

TEST(VotingRansac, RecoversTransformWith40PercentOutliers) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::normal_distribution<double> noise(0.0, 0.004);
  const Pose truth = make_pose(0.1, 0.25, -0.15, 0.3, 0.05, -0.2);
  std::vector<Eigen::Vector3d> src, dst;
  const int n = 200;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), 2.5 + u(rng));
    src.push_back(p);
    if (i % 5 < 2) dst.emplace_back(u(rng), u(rng), 2.5 + u(rng));  // 40 % wrong matches
    else dst.push_back(truth * p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  RansacParams params;
  params.iterations = 200;
  params.inlier_distance = 0.03;
  const RansacResult r = ransac_rigid(src, dst, params);
  ASSERT_TRUE(r.ok);
  EXPECT_LT(translation_error(r.T, truth), 0.005);
  EXPECT_LT(rotation_error(r.T, truth), 0.2 * M_PI / 180);
  EXPECT_GE(r.inliers.size(), size_t(0.55 * n));
  EXPECT_LE(r.inliers.size(), size_t(0.65 * n));
  // Plain least squares on all pairs is far off: the outliers matter.
  EXPECT_GT(translation_error(fit_rigid(src, dst), truth), 0.05);
}

TEST(PointToPlaneIcp, RecoversKnownMotionCoarseToFine) {
  PinholeIntrinsics k;  // 640x480, f = 525
  const Pose T_world_a = make_pose(0, 0, 0, 0, 0, 0);
  const Pose T_world_b = make_pose(0.06, -0.08, 0.04, 0.07, -0.04, 0.05);
  const cv::Mat depth_a = render_room(k, T_world_a), depth_b = render_room(k, T_world_b);
  const auto pa = build_depth_pyramid(depth_a, k, 3, 0.1, 10.0, true);
  const auto pb = build_depth_pyramid(depth_b, k, 3, 0.1, 10.0, true);
  const Pose truth = T_world_a.inverse() * T_world_b;  // T_a_b: target a, source b
  IcpParams params = precise_icp();
  params.max_distance = 0.15;
  const IcpResult r = icp_point_to_plane(pb, pa, Pose::Identity(), params);
  EXPECT_TRUE(r.converged);
  EXPECT_LT(translation_error(r.T_target_source, truth), 0.003);
  EXPECT_LT(rotation_error(r.T_target_source, truth), 0.2 * M_PI / 180);
  EXPECT_LT(r.rmse, 0.005);
  EXPECT_GT(r.overlap, 0.7);
  // Without ICP (identity start) the error is the whole motion.
  EXPECT_GT(translation_error(Pose::Identity(), truth), 0.09);
}

// The one-scan matcher (METHODS.md A2 step 1) must give what cv::BFMatcher gives: 2-NN ratio
// test, Hamming limit and mutual cross-check.
TEST(FeatureMatching, OneScanMatcherAgreesWithBFMatcher) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255), flip(0, 255);
  FrameFeatures a, b;
  a.descriptors.create(300, 32, CV_8U);
  b.descriptors.create(280, 32, CV_8U);
  for (int r = 0; r < b.descriptors.rows; ++r)
    for (int c = 0; c < 32; ++c) b.descriptors.at<uint8_t>(r, c) = uint8_t(byte(rng));
  for (int r = 0; r < a.descriptors.rows; ++r)
    for (int c = 0; c < 32; ++c)  // first 200 rows: noisy copies of b's rows, the rest random
      a.descriptors.at<uint8_t>(r, c) = r < 200 ? uint8_t(b.descriptors.at<uint8_t>(r, c) ^ (flip(rng) < 20 ? 1 << (c % 8) : 0))
                                                : uint8_t(byte(rng));
  const auto pairs = match_features(a, b, 0.8, 64);
  cv::BFMatcher matcher(cv::NORM_HAMMING, false);
  std::vector<std::vector<cv::DMatch>> forward;
  matcher.knnMatch(a.descriptors, b.descriptors, forward, 2);
  std::vector<cv::DMatch> backward;
  matcher.match(b.descriptors, a.descriptors, backward);
  std::vector<std::pair<int, int>> expected;
  for (const auto& knn : forward) {
    const cv::DMatch& m = knn[0];
    if (m.distance > 64 || m.distance > 0.8 * knn[1].distance || backward[m.trainIdx].trainIdx != m.queryIdx) continue;
    expected.emplace_back(m.queryIdx, m.trainIdx);
  }
  EXPECT_EQ(pairs, expected);
  EXPECT_GE(pairs.size(), 190u);
}

// A source-only pyramid completed for use as a target equals the full pyramid.
TEST(PointToPlaneIcp, CompletedSourcePyramidEqualsFullPyramid) {
  PinholeIntrinsics k;
  const cv::Mat depth = render_room(k, make_pose(0.02, 0.01, 0, 0.03, 0, 0));
  cv::Mat gray(depth.size(), CV_8UC1);
  cv::randu(gray, 0, 255);
  const auto full = build_depth_pyramid(depth, k, 3, 0.1, 10.0, true, gray);
  auto partial = build_depth_pyramid(depth, k, 3, 0.1, 10.0, true, gray, /*source_only=*/true);
  EXPECT_TRUE(partial[0].normals.empty());
  EXPECT_TRUE(partial[0].intensity_gradients.empty());
  complete_target_pyramid(partial, true);
  auto same = [](const cv::Mat& x, const cv::Mat& y) {  // NaN-aware
    cv::Mat xs = x.clone(), ys = y.clone();
    cv::patchNaNs(xs, -7.0);
    cv::patchNaNs(ys, -7.0);
    return cv::norm(xs.reshape(1), ys.reshape(1), cv::NORM_INF) == 0.0;
  };
  for (size_t l = 0; l < full.size(); ++l) {
    EXPECT_TRUE(same(full[l].vertices, partial[l].vertices)) << l;
    EXPECT_TRUE(same(full[l].normals, partial[l].normals)) << l;
    EXPECT_TRUE(same(full[l].intensity, partial[l].intensity)) << l;
    EXPECT_TRUE(same(full[l].intensity_gradients, partial[l].intensity_gradients)) << l;
  }
}

// A textured wall seen head-on: sliding along it leaves the point-to-plane cost flat, only the
// photometric term (joint ICP) sees the motion.
TEST(PointToPlaneIcp, PhotometricTermRecoversSlidingAlongTexturedPlane) {
  PinholeIntrinsics k;  // 640x480, f = 525
  const double tx = 0.04, ty = -0.025;
  auto render = [&](double ox, double oy, cv::Mat& depth, cv::Mat& gray) {
    depth.create(k.height, k.width, CV_32FC1);
    depth.setTo(2.0f);
    gray.create(k.height, k.width, CV_8UC1);
    for (int v = 0; v < k.height; ++v)
      for (int u = 0; u < k.width; ++u) {
        const double x = (u - k.cx) / k.fx * 2.0 + ox, y = (v - k.cy) / k.fy * 2.0 + oy;
        gray.at<uint8_t>(v, u) =
            cv::saturate_cast<uint8_t>(128 + 60 * std::sin(2 * M_PI * x / 0.3) * std::cos(2 * M_PI * y / 0.25));
      }
  };
  cv::Mat depth_a, gray_a, depth_b, gray_b;
  render(0, 0, depth_a, gray_a);
  render(tx, ty, depth_b, gray_b);
  const auto pa = build_depth_pyramid(depth_a, k, 3, 0.1, 10.0, true, gray_a);
  const auto pb = build_depth_pyramid(depth_b, k, 3, 0.1, 10.0, true, gray_b);
  ASSERT_FALSE(pa[2].intensity.empty());
  const Pose truth = make_pose(0, 0, 0, tx, ty, 0);  // T_a_b
  IcpParams geometric = precise_icp();
  geometric.max_distance = 0.15;
  geometric.photometric_weight = 0.0;
  const IcpResult g = icp_point_to_plane(pb, pa, Pose::Identity(), geometric);
  EXPECT_GT(translation_error(g.T_target_source, truth), 0.03);  // the slide is invisible to geometry
  IcpParams joint = geometric;
  joint.photometric_weight = 0.3;
  const IcpResult j = icp_point_to_plane(pb, pa, Pose::Identity(), joint);
  EXPECT_GT(j.photometric_matched, 1000);
  EXPECT_LT(translation_error(j.T_target_source, truth), 0.003);
  EXPECT_LT(rotation_error(j.T_target_source, truth), 0.2 * M_PI / 180);
}

TEST(DepthRepair, FillsHolesWithSameGreyMedianAndKeepsValidPixels) {
  const int w = 40, h = 30;
  cv::Mat gray(h, w, CV_8UC1, cv::Scalar(50));
  gray.colRange(20, w).setTo(200);  // two grey regions
  cv::Mat depth(h, w, CV_32FC1);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 0.2f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) depth.at<float>(y, x) = (x < 20 ? 1.0f : 3.0f) + u(rng);
  cv::Mat holes = depth.clone();
  holes.at<float>(10, 19) = 0;  // dark side, next to the bright region
  holes.at<float>(10, 20) = 0;  // bright side
  holes.at<float>(5, 5) = std::numeric_limits<float>::quiet_NaN();
  holes(cv::Rect(30, 20, 9, 9)).setTo(0);  // a hole wider than the window: centre stays invalid
  cv::Mat rgb;
  cv::cvtColor(gray, rgb, cv::COLOR_GRAY2BGR);
  DepthRepairParams params{3, 10.0, 1};
  const cv::Mat out = repair_depth(holes, rgb, params);
  // Valid pixels unchanged, bit for bit.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float d = holes.at<float>(y, x);
      if (d > 0) ASSERT_EQ(out.at<float>(y, x), d);
    }
  auto expected_median = [&](int cy, int cx) {
    std::vector<float> v;
    for (int y = cy - 3; y <= cy + 3; ++y)
      for (int x = cx - 3; x <= cx + 3; ++x) {
        if (y < 0 || x < 0 || y >= h || x >= w) continue;
        const float d = holes.at<float>(y, x);
        if (d > 0 && std::abs(int(gray.at<uint8_t>(y, x)) - int(gray.at<uint8_t>(cy, cx))) <= 10) v.push_back(d);
      }
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  EXPECT_EQ(out.at<float>(10, 19), expected_median(10, 19));
  EXPECT_LT(out.at<float>(10, 19), 1.3f);  // never takes the other region's depth
  EXPECT_EQ(out.at<float>(10, 20), expected_median(10, 20));
  EXPECT_GT(out.at<float>(10, 20), 2.9f);
  EXPECT_GT(out.at<float>(5, 5), 0.9f);
  EXPECT_EQ(out.at<float>(24, 34), 0.0f);  // nothing valid within r
  EXPECT_GT(out.at<float>(20, 30), 2.9f);  // hole border is filled
  EXPECT_THROW(repair_depth(cv::Mat(h, w, CV_16UC1), rgb, params), Error);
}

TEST(RandomFerns, SameImageMaxSimilarityDifferentImageLow) {
  FernParams params;
  FernDatabase db(params);
  std::mt19937 rng(5);
  auto random_frame = [&](cv::Mat& rgb, cv::Mat& depth) {
    rgb.create(480, 640, CV_8UC3);
    cv::randu(rgb, cv::Scalar::all(0), cv::Scalar::all(255));
    cv::resize(cv::Mat(rgb, cv::Rect(0, 0, 64, 48)).clone(), rgb, cv::Size(640, 480), 0, 0, cv::INTER_NEAREST);
    depth.create(480, 640, CV_32FC1);
    cv::randu(depth, 0.5, 4.0);
    cv::resize(cv::Mat(depth, cv::Rect(0, 0, 64, 48)).clone(), depth, cv::Size(640, 480), 0, 0, cv::INTER_NEAREST);
  };
  cv::Mat rgb_a, depth_a, rgb_b, depth_b;
  random_frame(rgb_a, depth_a);
  random_frame(rgb_b, depth_b);
  db.add(0, db.encode(rgb_a, depth_a));
  db.add(1, db.encode(rgb_b, depth_b));
  const auto sim_a = db.similarities(db.encode(rgb_a, depth_a));
  EXPECT_DOUBLE_EQ(sim_a[0], 1.0);
  // Chance agreement of 4-test ferns on unrelated images is about (2/3)^4 + blur effects.
  EXPECT_LT(sim_a[1], 0.6);
  cv::Mat rgb_c, depth_c;
  random_frame(rgb_c, depth_c);
  EXPECT_LT(db.max_similarity(db.encode(rgb_c, depth_c)), 0.6);
  // A slightly brighter copy is still recognised.
  cv::Mat brighter = rgb_a + cv::Scalar::all(4);
  EXPECT_GT(db.similarities(db.encode(brighter, depth_a))[0], 0.7);
}

TEST(PoseGraph, LoopEdgeReducesDriftOfNoisyLoop) {
  const int n = 24;
  std::vector<Pose> truth;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    truth.push_back(make_pose(0, a, 0, 2 * std::cos(a), 0, 2 * std::sin(a)));
  }
  std::mt19937 rng(11);
  std::normal_distribution<double> tn(0.0, 0.02), rn(0.0, 0.01);
  PoseGraph graph;
  Pose chain = truth[0];
  graph.add_vertex(0, chain);
  Matrix6d info = Matrix6d::Identity();
  info.topLeftCorner<3, 3>() *= 1.0 / (0.01 * 0.01);
  info.bottomRightCorner<3, 3>() *= 1.0 / (0.02 * 0.02);
  for (int i = 1; i < n; ++i) {
    const Pose measured = truth[i - 1].inverse() * truth[i] * make_pose(rn(rng), rn(rng), rn(rng), tn(rng), tn(rng), tn(rng));
    chain = chain * measured;
    graph.add_vertex(i, chain);
    graph.add_edge({i - 1, i, measured, info, false});
  }
  auto error = [&] {
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += (graph.pose(i).translation() - truth[i].translation()).squaredNorm();
    return std::sqrt(sum / n);
  };
  const double before = error();
  graph.add_edge({n - 1, 0, truth[n - 1].inverse() * truth[0], info * 10.0, true});
  const double energy_before = graph.total_error();
  ASSERT_TRUE(graph.optimize(100, 0.0));
  const double after = error();
  std::cout << "[pose graph] RMSE to truth before " << before << " m, after " << after << " m" << std::endl;
  EXPECT_LT(graph.total_error(), 0.1 * energy_before);
  EXPECT_LT(after, 0.5 * before);
  EXPECT_EQ(graph.loop_edge_count(), 1u);
  EXPECT_TRUE(graph.pose(0).isApprox(truth[0]));  // gauge fixed
}

TEST(Tracker, TracksRenderedRoomSequence) {
  CameraModel camera;
  TrackingConfig config;
  config.background_loop_closure = false;
  Tracker tracker(config, camera);
  std::vector<Pose> truth;
  for (int i = 0; i < 12; ++i) truth.push_back(make_pose(0.0, 0.01 * i, 0.004 * i, 0.012 * i, 0.003 * i, 0.006 * i));
  for (int i = 0; i < 12; ++i) {
    Frame f;
    f.index = i;
    f.timestamp = i / 30.0;
    f.depth = render_room(camera.depth, truth[i]);
    // Texture fixed to the world surfaces (moves with the scene) so ORB has something to find.
    cv::Mat gray(f.depth.size(), CV_8U, cv::Scalar(0));
    for (int y = 0; y < gray.rows; ++y)
      for (int x = 0; x < gray.cols; ++x) {
        const float z = f.depth.at<float>(y, x);
        if (!(z > 0)) continue;
        const Eigen::Vector3d w = truth[i] * camera.depth.backproject(x, y, z);
        const int cell = int(std::floor(w.x() * 6)) * 73856093 ^ int(std::floor(w.y() * 6)) * 19349663 ^
                         int(std::floor(w.z() * 6)) * 83492791;
        gray.at<uint8_t>(y, x) = uint8_t(40 + (unsigned(cell) % 7) * 30);
      }
    cv::GaussianBlur(gray, gray, cv::Size(3, 3), 0);
    cv::cvtColor(gray, f.rgb, cv::COLOR_GRAY2BGR);
    const TrackResult r = tracker.track(f);
    EXPECT_EQ(r.status, TrackingStatus::ok) << "frame " << i << " matches " << r.feature_matches << " inliers "
                                            << r.ransac_inliers << " icp rmse " << r.icp_rmse << " overlap "
                                            << r.icp_overlap << " prior " << r.used_motion_prior;
    if (i == 0) EXPECT_TRUE(r.is_keyframe);
  }
  const Trajectory traj = tracker.finish();
  ASSERT_EQ(traj.size(), 12u);
  for (int i = 0; i < 12; ++i) {
    const Pose expected = truth[0].inverse() * truth[i];
    EXPECT_LT(translation_error(traj[i].T_world_camera, expected), 0.005) << "frame " << i;
    EXPECT_LT(rotation_error(traj[i].T_world_camera, expected), 0.5 * M_PI / 180) << "frame " << i;
  }
  EXPECT_FALSE(tracker.keyframes().empty());
  Frame bad;
  bad.depth = cv::Mat(480, 640, CV_16UC1);
  bad.rgb = cv::Mat(480, 640, CV_8UC3);
  EXPECT_THROW(tracker.track(bad), Error);
}

TEST(TrackingConfig, ValidateRejectsBadValues) {
  TrackingConfig c;
  EXPECT_NO_THROW(c.validate());
  c.depth_repair.radius = 0;
  EXPECT_THROW(c.validate(), Error);
}
