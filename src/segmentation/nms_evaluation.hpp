#pragma once
// Measuring NMS variants on ground-truth instance images (issue 5: Soft-NMS vs hard NMS on
// side-by-side objects). A detector's raw output is emulated from ground truth: per visible
// instance several candidates whose boxes are jittered copies of its box, masks = the
// instance mask cropped to the jittered box (as YOLO crops), scores highest for the best
// aligned candidate. NMS then has to keep one candidate per object: hard NMS loses objects
// whose boxes overlap a better-scored neighbour's; Soft-NMS decays them instead.
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "segmentation/nms.hpp"

namespace semap {

struct JitterCandidateParams {
  int per_instance = 6;        ///< candidates per ground-truth instance
  double jitter = 0.08;        ///< box corner noise, std dev as a fraction of the box size
  double min_score = 0.5, max_score = 0.95;  ///< instance base score range
  int min_pixels = 150;        ///< instances with fewer visible pixels are not emulated / not counted
  uint64_t seed = 1;
};

struct CandidateSet {
  std::vector<ScoredBox> boxes;
  std::vector<cv::Mat> masks;  ///< CV_8UC1 0/255, image size
};

/// labels CV_8UC1 (class of each candidate = its majority label), instances CV_16UC1.
CandidateSet jittered_candidates(const cv::Mat& labels, const cv::Mat& instances, const JitterCandidateParams& params);

struct RecallFigures {
  int ground_truth = 0;  ///< instances with >= min_pixels
  int matched = 0;       ///< of those, matched one-to-one by a kept mask with IoU >= threshold
  int kept = 0;          ///< kept detections
  double recall() const { return ground_truth ? double(matched) / ground_truth : 0.0; }
  double precision() const { return kept ? double(matched) / kept : 0.0; }
  RecallFigures& operator+=(const RecallFigures& o) {
    ground_truth += o.ground_truth, matched += o.matched, kept += o.kept;
    return *this;
  }
};

/// Greedy one-to-one matching (highest IoU first) of kept masks to ground-truth instances.
RecallFigures match_masks(const cv::Mat& instances, const std::vector<cv::Mat>& kept_masks, int min_pixels,
                          double iou_threshold = 0.5);

}  // namespace semap
