#pragma once
// YOLO-seg (YOLOv8 / YOLO11 segmentation ONNX export) through OpenCV cv::dnn (METHODS.md C1).
// Outputs: detections [1, 4+nc+nm, N] (cx, cy, w, h in input pixels, nc sigmoid class scores,
// nm mask coefficients; [1, N, 4+nc+nm] is accepted too) and prototypes [1, nm, H/4, W/4].
// Grid sizes, nc and nm are all read from the tensor shapes: a 320 or 640 export works unchanged.
#include <filesystem>
#include <opencv2/dnn.hpp>

#include "semap/core/camera.hpp"
#include "segmentation/class_mapping.hpp"
#include "segmentation/nms.hpp"
#include "semap/segmentation/segmentation_config.hpp"
#include "segmentation/segmentation_utils.hpp"
#include "semap/segmentation/segmenter.hpp"

namespace semap {

class YoloSegmenter : public Segmenter {
 public:
  /// Throws semap::Error naming the file when it is missing or not a YOLO-seg ONNX model.
  YoloSegmenter(const std::filesystem::path& model_path, const SegmentationConfig& config);

  /// Instances (masks at the rgb image's resolution), plus labels/instance_ids painted from them.
  SegmentationResult segment(const Frame& frame) override;
  SegmentationResult segment_image(const cv::Mat& bgr);
  std::string name() const override { return "yolo:" + model_path_.string(); }

  /// Raw candidates of one image before NMS (for benchmarks and tests).
  struct Candidates {
    std::vector<ScoredBox> boxes;          ///< in image pixels
    std::vector<std::vector<float>> class_scores;  ///< model classes, per candidate
    cv::Mat coefficients;                  ///< candidates x nm, CV_32F
    cv::Mat prototypes;                    ///< nm x (Hp*Wp), CV_32F
    cv::Size proto_size;
    Letterbox letterbox;
    cv::Size image_size;
  };
  Candidates run_network(const cv::Mat& bgr);
  /// Candidates from the two output tensors (any input size / grid / class count, either
  /// detection layout); exposed so the decoder can be tested without a network.
  Candidates candidates_from_outputs(const cv::Mat& detections, const cv::Mat& prototypes, const Letterbox& letterbox,
                                     cv::Size image_size);
  /// NMS (as configured) + masks + class mapping on candidates.
  SegmentationResult decode(const Candidates& candidates);

  cv::Size input_size() const { return input_size_; }
  int model_class_count() const { return num_classes_; }
  const ClassMapping& class_mapping() const { return mapping_; }
  YoloConfig& yolo_config() { return config_.yolo; }

 private:
  void setup_classes(int num_classes);

  std::filesystem::path model_path_;
  SegmentationConfig config_;
  cv::dnn::Net net_;
  std::vector<std::string> output_names_;
  cv::Size input_size_;
  int num_classes_ = -1;
  ClassMapping mapping_;
};

}  // namespace semap
