// The fused surface along pixel rays (tsdf_raycast.hpp; frame-to-model tracking, METHODS.md A2):
// an analytic scene fused from noisy depth, read back from a new viewpoint with a noisy guide
// depth, must lie nearer the true surface than the noisy depth itself.
#include <gtest/gtest.h>

#include <random>

#include "analytic_scene.hpp"
#include "tsdf/semantic_tsdf.hpp"
#include "tsdf/tsdf_raycast.hpp"

using namespace semap;

namespace {
/// Kinect-like noise: sigma grows with depth (1.5 mm at 1 m, 6 mm at 3 m).
cv::Mat noisy(const cv::Mat& depth, std::mt19937& rng) {
  cv::Mat out = depth.clone();
  std::normal_distribution<float> n(0.0f, 1.0f);
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      float& z = out.at<float>(y, x);
      if (z > 0) z += (0.0012f + 0.0019f * (z - 0.4f) * (z - 0.4f)) * n(rng);
    }
  return out;
}
}  // namespace

TEST(TsdfRaycast, FusedSurfaceIsNearerTheTruthThanOneNoisyFrame) {
  const test::AnalyticScene scene;
  const PinholeIntrinsics K = test::AnalyticScene::intrinsics();
  TsdfConfig config;
  config.voxel_size = 0.02;
  SemanticTsdf tsdf(config);
  std::mt19937 rng(7);
  cv::Mat labels;
  for (const Pose& T : test::AnalyticScene::poses(12)) {
    IntegrationInput in;
    cv::Mat depth;
    scene.render(K, T, depth, labels);
    in.depth = noisy(depth, rng);
    in.intrinsics = K;
    in.T_world_camera = T;
    tsdf.integrate(in);
  }
  // A viewpoint between the fused ones, its own noisy depth as the guide.
  Pose T = Pose::Identity();
  T.linear() = Eigen::AngleAxisd(0.04, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.05, 0.02, 0.03);
  cv::Mat truth;
  scene.render(K, T, truth, labels);
  const cv::Mat guide = noisy(truth, rng);
  const cv::Mat model = surface_depth_along_rays(tsdf.map(), guide, K, T);
  ASSERT_EQ(model.size(), guide.size());
  double model_sq = 0, guide_sq = 0;
  int found = 0, valid = 0;
  for (int y = 0; y < truth.rows; ++y)
    for (int x = 0; x < truth.cols; ++x) {
      const float z = truth.at<float>(y, x), m = model.at<float>(y, x);
      if (!(z > 0)) continue;
      ++valid;
      if (!(m > 0)) continue;
      ++found;
      model_sq += double(m - z) * (m - z);
      guide_sq += double(guide.at<float>(y, x) - z) * (guide.at<float>(y, x) - z);
    }
  ASSERT_GT(valid, 0);
  const double model_rms = std::sqrt(model_sq / std::max(found, 1)), guide_rms = std::sqrt(guide_sq / std::max(found, 1));
  std::cout << "[raycast] found " << double(found) / valid << " of the pixels, rms to truth: fused "
            << model_rms * 1000 << " mm, one frame " << guide_rms * 1000 << " mm" << std::endl;
  EXPECT_GT(double(found) / valid, 0.9);  // the view is inside the fused ones
  EXPECT_LT(model_rms, 0.6 * guide_rms);  // twelve frames average the noise
  // Pixels without a guide depth, or a guide far from every surface, find none.
  cv::Mat far(guide.size(), CV_32FC1, cv::Scalar(0.5f));
  far.at<float>(0, 0) = 0.0f;
  const cv::Mat none = surface_depth_along_rays(tsdf.map(), far, K, T);
  EXPECT_EQ(cv::countNonZero(none), 0);
}
