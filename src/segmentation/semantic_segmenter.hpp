#pragma once
// Semantic segmentation ONNX model through cv::dnn (METHODS.md A5): per-pixel logits, NCHW
// [1,C,h,w] or NHWC [1,h,w,C] (detected from the shape), softmax + argmax, mapped to project
// classes (model classes mapping to the same project class have their probabilities summed).
#include <filesystem>
#include <opencv2/dnn.hpp>

#include "segmentation/class_mapping.hpp"
#include "semap/segmentation/segmentation_config.hpp"
#include "semap/segmentation/segmenter.hpp"

namespace semap {

class SemanticSegmenter : public Segmenter {
 public:
  /// Throws semap::Error naming the file when it is missing or not a 1-input 1-output
  /// image-to-logits ONNX model.
  SemanticSegmenter(const std::filesystem::path& model_path, const SegmentationConfig& config);

  /// labels (CV_8UC1), confidence (CV_32FC1, top probability) and, when configured,
  /// probabilities (CV_32FC(kNumClasses)), all at the rgb image's resolution. No instances.
  SegmentationResult segment(const Frame& frame) override;
  SegmentationResult segment_image(const cv::Mat& bgr);
  std::string name() const override { return "semantic:" + model_path_.string(); }

  cv::Size input_size() const { return input_size_; }
  bool input_is_nhwc() const { return nhwc_input_; }
  const ClassMapping& class_mapping() const { return mapping_; }

 private:
  std::filesystem::path model_path_;
  SegmentationConfig config_;
  cv::dnn::Net net_;
  cv::Size input_size_;
  bool nhwc_input_ = false;
  int num_classes_ = -1;
  ClassMapping mapping_;
};

}  // namespace semap
