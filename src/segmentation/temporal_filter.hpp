#pragma once
// Temporal label filter (METHODS.md B1). A frame's pixel label is kept only when previous
// frames agree; otherwise the pixel becomes unlabelled (0) for this frame.
//  - "seed": the seed's 5-frame intersection: the SAME PIXEL must carry the same label in the
//    previous window-1 frames (exact under a static camera; under motion, object borders
//    move and correct labels are dropped).
//  - "warped": each pixel is back-projected with its depth, moved by the relative pose into
//    every previous frame, projected, and compared there when that frame sees the same
//    surface (|z_warped - depth_prev| <= depth_tolerance_m + depth_tolerance_rel * z).
//    Pixels without depth cannot be warped and get no label.
// Both keep a pixel when at least min_agree previous frames agree (min_agree = window-1 is
// the seed's rule). "warped" also keeps it when every previous frame that sees the point
// agrees and at least min_views do (points that entered the view recently, or were occluded,
// are not dropped for lack of history). The first frames, before enough history exists,
// yield no labels.
#include <deque>
#include <opencv2/core.hpp>

#include "semap/core/camera.hpp"
#include "semap/core/pose.hpp"
#include "semap/segmentation/segmentation_config.hpp"
#include "semap/segmentation/segmenter.hpp"

namespace semap {

class TemporalLabelFilter {
 public:
  /// `intrinsics`: the camera of the label/depth images (depth camera after registration).
  TemporalLabelFilter(const TemporalFilterConfig& config, const PinholeIntrinsics& intrinsics);

  /// Filters `labels` (CV_8UC1) and remembers the frame. `depth` (CV_32FC1 m) and
  /// T_world_camera are only needed by "warped". method "none" returns the labels unchanged.
  cv::Mat apply(const cv::Mat& labels, const cv::Mat& depth = {}, const Pose& T_world_camera = Pose::Identity());

  /// Filters result.labels; instance ids and masks lose the dropped pixels, instances left
  /// without pixels are removed, probabilities/confidence are left as computed.
  SegmentationResult apply(const SegmentationResult& result, const cv::Mat& depth, const Pose& T_world_camera);

  void reset() { history_.clear(); }
  const TemporalFilterConfig& config() const { return config_; }

 private:
  struct Past {
    cv::Mat labels, depth;
    Pose T_world_camera;
  };
  cv::Mat keep_mask_seed(const cv::Mat& labels) const;
  cv::Mat keep_mask_warped(const cv::Mat& labels, const cv::Mat& depth, const Pose& T_world_camera) const;

  TemporalFilterConfig config_;
  PinholeIntrinsics intrinsics_;
  std::deque<Past> history_;  ///< most recent first, at most window-1
};

}  // namespace semap
