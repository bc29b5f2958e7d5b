#pragma once
// The segmenter interface (issue 5): per frame, instances and/or a semantic label image, in
// PROJECT class ids (core/labels.hpp). Model class ids are mapped before they leave here.
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "semap/core/frame.hpp"
#include "semap/core/labels.hpp"

namespace semap {

struct InstanceDetection {
  uint16_t id = 0;                 ///< 1-based within the frame; matches SegmentationResult::instance_ids
  ClassId class_id = 0;            ///< project class id
  float score = 0.f;               ///< confidence of class_id
  std::vector<float> class_scores; ///< optional, size kNumClasses, project class scores
  cv::Mat mask;                    ///< CV_8UC1 0/255 at the frame's depth resolution
  cv::Rect box;                    ///< in the same image
};

struct SegmentationResult {
  size_t frame_index = 0;          ///< the frame this was computed on
  double timestamp = 0.0;
  std::vector<InstanceDetection> instances;
  cv::Mat labels;                  ///< optional CV_8UC1 project class ids, 0 = unlabelled
  cv::Mat instance_ids;            ///< optional CV_16UC1, 0 = none
  cv::Mat confidence;              ///< optional CV_32FC1, confidence of `labels` in [0, 1]
  cv::Mat probabilities;           ///< optional CV_32FC(kNumClasses) per-pixel class probabilities

  bool has_labels() const { return !labels.empty(); }
  bool empty() const { return instances.empty() && labels.empty(); }
};

class Segmenter {
 public:
  virtual ~Segmenter() = default;
  virtual SegmentationResult segment(const Frame& frame) = 0;
  virtual std::string name() const = 0;
  /// True when segmenting costs next to nothing (labels read from files, ground truth): the
  /// Mapper then labels every frame for the TSDF, not only the scheduled ones.
  virtual bool is_cheap() const { return false; }
};

}  // namespace semap
