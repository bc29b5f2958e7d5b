#pragma once
// Segmenters that read labels instead of running a network (issue 5, item 4):
// - GroundTruthSegmenter: Frame.labels / Frame.instances as loaded by the dataset readers
//   (synthetic, YCB-Video), already in project class ids.
// - PrecomputedSegmenter: NAME.label.png + NAME.instances.png + NAME.json per image from any
//   external tool (Mask R-CNN, Mask2Former, ... run elsewhere), NAME = the rgb file's stem.
//   It reads exactly what `semap segment` writes (segmentation_io.hpp documents the JSON).
#include <filesystem>

#include "semap/segmentation/segmentation_config.hpp"
#include "semap/segmentation/segmenter.hpp"

namespace semap {

/// Instances from a label + instance image pair (project ids): one instance per non-zero
/// instance id, its class the majority label under its mask, score 1, one-hot class scores.
/// Without an instance image, each non-stuff class present becomes one instance. More instance
/// ids than check_instance_count allows throw semap::Error naming `where` (the instance image).
SegmentationResult result_from_label_images(const cv::Mat& labels, const cv::Mat& instances,
                                            const std::string& where = "instance image");

class GroundTruthSegmenter : public Segmenter {
 public:
  /// Throws semap::Error(frame.rgb_path, ...) when the frame carries no labels.
  SegmentationResult segment(const Frame& frame) override;
  std::string name() const override { return "groundtruth"; }
  bool is_cheap() const override { return true; }
};

class PrecomputedSegmenter : public Segmenter {
 public:
  /// Throws semap::Error naming the folder when it does not exist.
  PrecomputedSegmenter(const std::filesystem::path& dir, const SegmentationConfig& config);
  /// Throws semap::Error naming the missing/corrupt file.
  SegmentationResult segment(const Frame& frame) override;
  /// Reads DIR/NAME.* directly.
  SegmentationResult read(const std::string& name) const;
  std::string name() const override { return "precomputed:" + dir_.string(); }
  bool is_cheap() const override { return true; }

 private:
  std::filesystem::path dir_;
  SegmentationConfig config_;
};

}  // namespace semap
