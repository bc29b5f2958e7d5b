#pragma once
// Helpers shared by the segmenters: letterboxing, painting instances into label images.
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

#include "semap/segmentation/segmenter.hpp"

namespace semap {

/// Letterbox transform: network pixel = image pixel * scale + (pad_x, pad_y).
struct Letterbox {
  double scale = 1.0;
  int pad_x = 0, pad_y = 0;
  cv::Size input;  ///< network input size
};

/// Resizes `image` keeping its aspect ratio into `input`, padding with `pad_value`
/// (centred, as Ultralytics does). Returns the padded image and the transform.
cv::Mat letterbox_image(const cv::Mat& image, cv::Size input, int pad_value, Letterbox& transform);

/// Fills result.labels (CV_8UC1) and result.instance_ids (CV_16UC1) of size `size` from the
/// instance masks; where masks overlap the higher-scoring instance wins.
void paint_instances(SegmentationResult& result, cv::Size size);

/// Issue 44: every instance of a frame carries a full-frame mask (count x width x height
/// bytes), so a frame's instances are bounded by this much mask memory (at 640x480: 873).
constexpr uint64_t kMaxInstanceMaskBytes = uint64_t{256} << 20;
/// Throws semap::Error(where, ...) when `count` instance masks of `size` exceed
/// kMaxInstanceMaskBytes; call before the masks are made.
void check_instance_count(size_t count, cv::Size size, const std::string& where);

/// One-hot class-score vector of size kNumClasses.
std::vector<float> one_hot_scores(ClassId c, float score = 1.f);

}  // namespace semap
