#pragma once
// Non-maximum suppression over scored boxes (METHODS.md C1): Gaussian Soft-NMS and hard NMS.
#include <opencv2/core.hpp>
#include <vector>

namespace semap {

struct ScoredBox {
  cv::Rect2f box;   ///< x, y, width, height
  float score = 0.f;
  int class_id = 0; ///< boxes of different classes never suppress each other unless class-agnostic
};

double box_iou(const cv::Rect2f& a, const cv::Rect2f& b);

struct NmsResult {
  int index;    ///< into the input vector
  float score;  ///< after decay (Soft-NMS) or unchanged (hard)
};

/// Hard NMS: greedily keeps the best box, removes every box with IoU > iou_threshold.
/// Returns kept boxes in descending score, at most max_keep.
std::vector<NmsResult> hard_nms(const std::vector<ScoredBox>& boxes, double iou_threshold, bool class_agnostic,
                                int max_keep);

/// Gaussian Soft-NMS (Bodla et al. 2017, METHODS.md C1): after picking the current best box
/// b_max, every remaining box decays s_i <- s_i * exp(-IoU(b_max, b_i)^2 / sigma). We use the
/// Soft-NMS paper's form exp(-IoU^2/sigma) (the seed prints exp(-IoU/sigma^2)): it leaves
/// low-overlap neighbours almost untouched (IoU 0.3, sigma 0.5: x0.84) and crushes duplicates
/// (IoU 0.9: x0.20). Boxes whose score falls under score_floor are removed. Returns kept boxes in
/// pick order (descending decayed score), at most max_keep.
std::vector<NmsResult> soft_nms(const std::vector<ScoredBox>& boxes, double sigma, double score_floor,
                                bool class_agnostic, int max_keep);

}  // namespace semap
