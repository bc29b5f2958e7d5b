// RepairArchive: a frame's repaired depth comes back bit-identical from its depth image plus the
// archived fills; the budget and values that would not convert back exactly keep frames out.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <cstring>
#include <random>

#include "pipeline/refresh_archive.hpp"
#include "tracking/depth_repair.hpp"

namespace semap {
namespace {

constexpr double kScale = 5000.0;  // TUM: depth units of 0.2 mm

/// Depth as read_depth_image makes it (16-bit units * float(1/scale)), with holes.
cv::Mat decoded_depth_with_holes(std::mt19937& rng) {
  cv::Mat depth(120, 160, CV_32FC1);
  const float inv_scale = static_cast<float>(1.0 / kScale);
  std::uniform_int_distribution<int> units(4000, 20000);
  std::bernoulli_distribution hole(0.15);
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) depth.at<float>(y, x) = hole(rng) ? 0.0f : units(rng) * inv_scale;
  return depth;
}

TEST(RepairArchive, RestoresTheRepairedDepthBitForBit) {
  std::mt19937 rng(1);
  const cv::Mat decoded = decoded_depth_with_holes(rng);
  cv::Mat grey(decoded.size(), CV_8UC1, cv::Scalar(100));
  const cv::Mat repaired = repair_depth(decoded, grey, DepthRepairParams{2, 20.0, 3});
  ASSERT_GT(cv::countNonZero(decoded != repaired), 1000) << "the repair must fill holes for the test to mean anything";

  RepairArchive archive(kScale, 1 << 20);
  archive.store(7, decoded, repaired);
  ASSERT_TRUE(archive.has(7));
  EXPECT_FALSE(archive.has(8));
  cv::Mat restored = decoded.clone();
  archive.apply(7, restored);
  EXPECT_EQ(std::memcmp(restored.data, repaired.data, repaired.total() * sizeof(float)), 0);
  EXPECT_LT(archive.bytes(), repaired.total() * sizeof(float) / 4) << "fills only, not the whole frame";
}

TEST(RepairArchive, BudgetAndInexactValuesKeepFramesOut) {
  std::mt19937 rng(2);
  cv::Mat decoded = decoded_depth_with_holes(rng);
  decoded.at<float>(3, 4) = 0.0f;  // a hole the "repair" fills with 1 m (5000 units)
  cv::Mat repaired = decoded.clone();
  repaired.at<float>(3, 4) = 5000 * static_cast<float>(1.0 / kScale);

  RepairArchive tiny(kScale, 16);  // smaller than any entry
  tiny.store(0, decoded, repaired);
  EXPECT_FALSE(tiny.has(0));

  RepairArchive off(kScale, 0);
  off.store(0, decoded, repaired);
  EXPECT_FALSE(off.has(0));

  RepairArchive archive(kScale, 1 << 20);
  cv::Mat inexact = repaired.clone();
  inexact.at<float>(3, 4) = 1.23456789e-3f * 1001.0f;  // not a multiple of 1/5000 m
  archive.store(1, decoded, inexact);
  EXPECT_FALSE(archive.has(1)) << "a fill that would not come back exactly must not be archived";
  archive.store(2, decoded, repaired);
  EXPECT_TRUE(archive.has(2));
}

}  // namespace
}  // namespace semap
