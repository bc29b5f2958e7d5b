#pragma once
// Panoptic segmentation from two networks (issue 38; METHODS B1 names instance / semantic /
// panoptic segmentation): a semantic model labels stuff and furniture at every pixel (with
// per-pixel probabilities for the Bayesian layer, METHODS A6), an instance model finds countable
// objects (METHODS C1). The two existing segmenters are composed; neither's decoding is repeated.
//
// Per pixel: inside an instance mask the instance wins (its class, id and score), whatever the
// semantic class there (the instance model is the one trained to separate and name objects);
// elsewhere the semantic label fills in, semantic "thing" classes (chair, table, sofa, bed)
// included, without an instance id. Pixels neither network labels stay 0.
#include <memory>
#include <string>

#include "semap/segmentation/segmenter.hpp"

namespace semap {

/// Combines one image's semantic result (labels, optional confidence and probabilities, no
/// instances) with its instance result (instances with masks; instance_ids painted from them
/// when present, else painted here: the higher score wins an overlap). Both must have the
/// same image size (throws semap::Error otherwise). Instances scoring below
/// `min_instance_score` stay in the instance list (the object map weighs them by score) but do
/// not overwrite the semantic pixels. Inside a kept instance: label = its class,
/// instance id kept, confidence = its score, probabilities = its score on its class and the rest
/// spread evenly over the other classes (a label-only observation, METHODS A6). Elsewhere the
/// semantic pixel as it was. The result carries the instance result's instances.
/// Consumes `semantic`: its images are updated in place and returned (no copy of the
/// per-pixel probabilities); cv::Mat copies share data, so pass clones to keep the originals.
SegmentationResult combine_panoptic(SegmentationResult&& semantic, const SegmentationResult& instances,
                                    double min_instance_score = 0.0);

class PanopticSegmenter : public Segmenter {
 public:
  /// Milliseconds spent in the last segment() call, per part.
  struct Timing {
    double semantic_ms = 0.0, instance_ms = 0.0, combine_ms = 0.0;
  };

  /// Both results must have the same size: make_segmenter() registers each network's result to
  /// depth pixels when the camera needs it. Throws semap::Error when either is null.
  PanopticSegmenter(std::unique_ptr<Segmenter> semantic, std::unique_ptr<Segmenter> instance,
                    double min_instance_score = 0.0);

  SegmentationResult segment(const Frame& frame) override;
  /// "panoptic:SEMANTIC_NAME+INSTANCE_NAME", e.g. "panoptic:semantic:A.onnx+yolo:B.onnx": a spec
  /// make_segmenter() accepts, naming both models (report.json).
  std::string name() const override;
  const Timing& last_timing() const { return timing_; }
  /// The two networks, for a caller that schedules each on its own frames (the Mapper, issue 38)
  /// and combines them with combine_panoptic(). Not thread-safe against segment().
  Segmenter& semantic() { return *semantic_; }
  Segmenter& instance() { return *instance_; }
  double min_instance_score() const { return min_instance_score_; }

 private:
  std::unique_ptr<Segmenter> semantic_, instance_;
  double min_instance_score_;
  Timing timing_;
};

}  // namespace semap
