// Issue 44, class 2: a frame's instance ids size one full-frame mask each, so their count is
// bounded (check_instance_count: kMaxInstanceMaskBytes of masks) before any mask is made:
// 65,535 ids in a ground-truth instance image, or listed in a precomputed segmentation's JSON,
// are one error naming the file; a frame with a realistic number of instances still reads.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "segmentation/groundtruth_segmenter.hpp"
#include "segmentation/segmentation_utils.hpp"
#include "semap/core/error.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;

/// A 256x256 frame whose every pixel is its own instance (ids 1..65535, one pixel left 0).
cv::Mat every_pixel_an_instance() {
  cv::Mat ids(256, 256, CV_16UC1);
  for (int i = 0; i < 256 * 256; ++i) ids.at<uint16_t>(i / 256, i % 256) = static_cast<uint16_t>(i);
  return ids;
}

TEST(InstanceBounds, GroundTruthImageWithSixtyFiveThousandIdsIsOneError) {
  const cv::Mat labels(256, 256, CV_8UC1, cv::Scalar(5));
  try {
    result_from_label_images(labels, every_pixel_an_instance(), "frame-000001.instances.png");
    FAIL() << "65,535 instance masks were made";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("frame-000001.instances.png: 65535 instances in one 256x256 frame"), std::string::npos) << message;
  }
  // 40 instances of a realistic frame: one mask each.
  cv::Mat few = cv::Mat::zeros(256, 256, CV_16UC1);
  for (int k = 0; k < 40; ++k) few(cv::Rect((k % 8) * 32, (k / 8) * 32, 20, 20)).setTo(k + 1);
  EXPECT_EQ(result_from_label_images(labels, few).instances.size(), 40u);
}

TEST(InstanceBounds, PrecomputedSegmentationsAreBoundedToo) {
  test::TempDir dir("semap_instance_bounds");
  cv::imwrite((dir.path() / "f.label.png").string(), cv::Mat(256, 256, CV_16UC1, cv::Scalar(5)));
  cv::imwrite((dir.path() / "f.instances.png").string(), every_pixel_an_instance());
  // Without a JSON instance list: instances from the image.
  std::ofstream(dir.path() / "f.json") << "{}";
  PrecomputedSegmenter segmenter(dir.path(), SegmentationConfig{});
  try {
    segmenter.read("f");
    FAIL() << "65,535 instance masks were made";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find((dir.path() / "f.instances.png").string() + ": 65535 instances"), std::string::npos) << e.what();
  }
  // A JSON listing 65,535 instances.
  {
    std::ofstream json(dir.path() / "f.json");
    json << "{\"instances\": [";
    for (int i = 1; i < 65536; ++i) json << (i > 1 ? "," : "") << "{\"id\":" << i << ",\"class_id\":5}";
    json << "]}";
  }
  try {
    segmenter.read("f");
    FAIL() << "65,535 instance masks were made";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find((dir.path() / "f.json").string() + ": 65535 instances"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace semap
