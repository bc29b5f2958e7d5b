// Depth and segmentation noise models of the synthetic world.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <set>

#include "semap/core/labels.hpp"
#include "synth/depth_noise.hpp"
#include "semap/synth/segmentation_noise.hpp"

namespace semap {
namespace {

struct Stats {
  double mean = 0, std = 0;
  int valid = 0;
};
Stats error_stats(const cv::Mat& noisy, double truth) {
  Stats s;
  double sum = 0, sum2 = 0;
  for (int v = 0; v < noisy.rows; ++v)
    for (int u = 0; u < noisy.cols; ++u) {
      const float z = noisy.at<float>(v, u);
      if (z <= 0) continue;
      sum += z - truth;
      sum2 += (z - truth) * (z - truth);
      ++s.valid;
    }
  s.mean = sum / s.valid;
  s.std = std::sqrt(sum2 / s.valid - s.mean * s.mean);
  return s;
}

TEST(SynthDepthNoise, AxialSigmaMatchesNguyenModelAt2m) {
  DepthNoiseParams p;
  p.quantise_disparity = false;
  const cv::Mat depth(480, 640, CV_32FC1, cv::Scalar(2.0));
  const cv::Mat cosi(480, 640, CV_32FC1, cv::Scalar(1.0));
  const double sigma = 0.0012 + 0.0019 * (2.0 - 0.4) * (2.0 - 0.4);
  EXPECT_NEAR(depth_noise_sigma(p, 2.0), sigma, 1e-12);
  const Stats s = error_stats(apply_depth_noise(depth, cosi, 525.0, 42, p), 2.0);
  EXPECT_EQ(s.valid, 640 * 480);
  EXPECT_NEAR(s.std, sigma, 0.2 * sigma);
  EXPECT_LT(std::abs(s.mean), 0.1 * sigma);
  // At 1 m the noise is much smaller (z^2 growth).
  const cv::Mat near(480, 640, CV_32FC1, cv::Scalar(1.0));
  const Stats s1 = error_stats(apply_depth_noise(near, cosi, 525.0, 43, p), 1.0);
  EXPECT_NEAR(s1.std, depth_noise_sigma(p, 1.0), 0.2 * depth_noise_sigma(p, 1.0));
  EXPECT_LT(s1.std, 0.5 * s.std);
}

TEST(SynthDepthNoise, DisparityQuantisationAddsTheExpectedStep) {
  DepthNoiseParams p;  // quantisation on by default
  const cv::Mat depth(480, 640, CV_32FC1, cv::Scalar(2.0));
  const Stats s = error_stats(apply_depth_noise(depth, cv::Mat(), 525.0, 7, p), 2.0);
  const double step = 2.0 * 2.0 / (525.0 * 0.075) * 0.125;  // dz = z^2 / (f b) * disparity step
  const double sigma = depth_noise_sigma(p, 2.0);
  const double expected = std::sqrt(sigma * sigma + step * step / 12.0);
  EXPECT_NEAR(s.std, expected, 0.2 * expected);
  // Every value sits on a disparity level.
  const cv::Mat noisy = apply_depth_noise(depth, cv::Mat(), 525.0, 7, p);
  const double d = 525.0 * 0.075 / noisy.at<float>(10, 10) / 0.125;
  EXPECT_NEAR(d, std::round(d), 1e-3);
}

TEST(SynthDepthNoise, MissingDepthAtGrazingAnglesEdgesAndRange) {
  DepthNoiseParams p;
  p.edge_dropout = 1.0;
  cv::Mat depth(100, 100, CV_32FC1, cv::Scalar(1.5));
  depth(cv::Rect(0, 0, 50, 100)).setTo(1.0);  // step edge at u = 50
  depth.at<float>(5, 75) = 0.2;               // too close
  cv::Mat cosi(100, 100, CV_32FC1, cv::Scalar(1.0));
  cosi(cv::Rect(80, 0, 20, 100)).setTo(0.1);  // ~84 deg incidence
  const cv::Mat noisy = apply_depth_noise(depth, cosi, 525.0, 3, p);
  for (int v = 0; v < 100; ++v) {
    EXPECT_EQ(noisy.at<float>(v, 50), 0.f) << "far side of the depth edge";
    EXPECT_GT(noisy.at<float>(v, 49), 0.f) << "near side stays";
    EXPECT_GT(noisy.at<float>(v, 60), 0.f);
    for (int u = 80; u < 100; ++u) EXPECT_EQ(noisy.at<float>(v, u), 0.f) << "grazing angle";
  }
  EXPECT_EQ(noisy.at<float>(5, 75), 0.f);
  // Deterministic for a seed.
  EXPECT_EQ(cv::norm(noisy, apply_depth_noise(depth, cosi, 525.0, 3, p), cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(noisy, apply_depth_noise(depth, cosi, 525.0, 4, p), cv::NORM_INF), 0);
}

// A grid of rectangular instances (touching neighbours) over a floor background.
void make_grid(cv::Mat& labels, cv::Mat& instances, int nx = 16, int ny = 12) {
  labels = cv::Mat(480, 640, CV_8UC1, cv::Scalar(id(Label::kFloor)));
  instances = cv::Mat(480, 640, CV_16UC1, cv::Scalar(0));
  const Label classes[] = {Label::kChair, Label::kTable, Label::kCup, Label::kBox};
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const cv::Rect r(i * 40, j * 40, 40, 40);
      if ((i + j) % 5 == 4) continue;  // some background between
      const int inst = 1 + j * nx + i;
      instances(r).setTo(inst);
      labels(r).setTo(id(classes[inst % 4]));
    }
}

TEST(SynthSegmentationNoise, FlickerRateMatchesRequested) {
  cv::Mat labels, instances;
  make_grid(labels, instances);
  SegmentationNoiseParams p;
  p.flicker_rate = 0.2;
  p.miss_rate = p.merge_rate = p.border_rate = 0;
  int regions = 0, flickered = 0;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    const auto [nl, ni] = apply_segmentation_noise(labels, instances, seed, p);
    EXPECT_EQ(cv::norm(ni, instances, cv::NORM_INF), 0) << "flicker keeps instance ids";
    std::set<int> seen;
    for (int v = 0; v < 480; v += 40)
      for (int u = 0; u < 640; u += 40) {
        const int inst = instances.at<uint16_t>(v, u);
        if (inst == 0 || !seen.insert(inst).second) continue;
        ++regions;
        flickered += nl.at<uint8_t>(v, u) != labels.at<uint8_t>(v, u);
        // One class per region.
        EXPECT_EQ(nl.at<uint8_t>(v + 39, u + 39), nl.at<uint8_t>(v, u));
      }
  }
  EXPECT_NEAR(static_cast<double>(flickered) / regions, 0.2, 0.03) << regions << " regions";
}

TEST(SynthSegmentationNoise, MissMergeAndBorders) {
  cv::Mat labels, instances;
  make_grid(labels, instances);
  SegmentationNoiseParams p;
  p.flicker_rate = 0;
  p.merge_rate = 0;
  p.border_rate = 0;
  p.miss_rate = 0.3;
  int total = 0, missed = 0;
  for (uint64_t seed = 0; seed < 10; ++seed) {
    const auto [nl, ni] = apply_segmentation_noise(labels, instances, seed, p);
    for (int v = 20; v < 480; v += 40)
      for (int u = 20; u < 640; u += 40) {
        if (instances.at<uint16_t>(v, u) == 0) continue;
        ++total;
        if (ni.at<uint16_t>(v, u) == 0) {
          ++missed;
          EXPECT_EQ(nl.at<uint8_t>(v, u), 0);
        }
      }
  }
  EXPECT_NEAR(static_cast<double>(missed) / total, 0.3, 0.04);

  // merge_rate 1: every touching pair merges, so connected touching blocks share one id.
  p.miss_rate = 0;
  p.merge_rate = 1.0;
  const auto [ml, mi] = apply_segmentation_noise(labels, instances, 1, p);
  EXPECT_EQ(mi.at<uint16_t>(20, 20), mi.at<uint16_t>(20, 60));
  EXPECT_EQ(ml.at<uint8_t>(20, 20), ml.at<uint8_t>(20, 60));
  // merge_rate 0.3: some but not all pairs merge.
  p.merge_rate = 0.3;
  const auto [sl, si] = apply_segmentation_noise(labels, instances, 2, p);
  std::set<int> before, after;
  for (int v = 20; v < 480; v += 40)
    for (int u = 20; u < 640; u += 40) {
      if (instances.at<uint16_t>(v, u)) before.insert(instances.at<uint16_t>(v, u));
      if (si.at<uint16_t>(v, u)) after.insert(si.at<uint16_t>(v, u));
    }
  EXPECT_LT(after.size(), before.size() * 0.9);
  EXPECT_GT(after.size(), before.size() * 0.3);

  // Borders: erosion removes pixels, dilation adds pixels; the change is at most border_px wide.
  p.merge_rate = 0;
  p.border_rate = 1.0;
  p.border_px = 3;
  const auto [bl, bi] = apply_segmentation_noise(labels, instances, 5, p);
  const double changed = cv::countNonZero(bi != instances) / double(640 * 480);
  EXPECT_GT(changed, 0.02);
  EXPECT_LT(changed, 0.3);
  for (int v = 20; v < 480; v += 40)
    for (int u = 20; u < 640; u += 40) EXPECT_EQ(bi.at<uint16_t>(v, u), instances.at<uint16_t>(v, u)) << "centres stay";
}

// Over-segmentation: a split instance keeps its class; its far half gets an id of its own that
// no other instance has, and the near half keeps the original id.
TEST(SynthSegmentationNoise, SplitGivesTheFarHalfANewIdOfTheSameClass) {
  cv::Mat labels, instances;
  make_grid(labels, instances);
  SegmentationNoiseParams p;
  p.flicker_rate = p.miss_rate = p.merge_rate = p.border_rate = 0;
  p.split_rate = 0.5;
  const auto [nl, ni] = apply_segmentation_noise(labels, instances, 3, p);
  EXPECT_EQ(cv::countNonZero(nl != labels), 0) << "a split changes no class";
  int split = 0, whole = 0;
  std::set<int> new_ids;
  for (int v = 0; v < 480; v += 40)
    for (int u = 0; u < 640; u += 40) {
      const int original = instances.at<uint16_t>(v + 5, u + 5);
      if (original == 0) continue;
      EXPECT_EQ(ni.at<uint16_t>(v + 5, u + 5), original) << "the near half keeps its id";
      const int far = ni.at<uint16_t>(v + 35, u + 35);
      if (far == original) {
        ++whole;
        continue;
      }
      ++split;
      EXPECT_GT(far, 16 * 12) << "a new id, not another instance's";
      EXPECT_TRUE(new_ids.insert(far).second) << "one new id per split instance";
    }
  EXPECT_GT(split, whole / 2);
  EXPECT_LT(split, whole * 2);
}

TEST(SynthSegmentationNoise, PureDeterministicAndFast) {
  cv::Mat labels, instances;
  make_grid(labels, instances);
  const cv::Mat labels_copy = labels.clone();
  SegmentationNoiseParams p;
  p.flicker_rate = 0.2;
  p.pixel_flicker_rate = 0.01;
  const auto [a_l, a_i] = apply_segmentation_noise(labels, instances, 9, p);
  const auto [b_l, b_i] = apply_segmentation_noise(labels, instances, 9, p);
  const auto [c_l, c_i] = apply_segmentation_noise(labels, instances, 10, p);
  EXPECT_EQ(cv::norm(labels, labels_copy, cv::NORM_INF), 0) << "input untouched";
  EXPECT_EQ(cv::norm(a_l, b_l, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(a_i, b_i, cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(a_l, c_l, cv::NORM_L1), 0);
  const double pixel_changes = cv::countNonZero(a_l != labels) / double(640 * 480);
  EXPECT_GT(pixel_changes, 0.01);
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 20; ++i) apply_segmentation_noise(labels, instances, i, p);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / 20;
  EXPECT_LT(ms, 40.0) << "per 640x480 frame";
  RecordProperty("seg_noise_ms_per_frame", std::to_string(ms));
  // Bad input types are errors, not crashes.
  EXPECT_THROW(apply_segmentation_noise(instances, labels, 1, p), std::exception);
}

}  // namespace
}  // namespace semap
