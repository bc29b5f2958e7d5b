#pragma once
// Noisy segmentation for robustness tests (issue 2 "noisy-segmentation mode"). Turns perfect
// label/instance images into what an imperfect instance segmenter would give, per frame:
//  - flicker: each region (an instance, or a stuff class) gets a wrong class with probability
//    flicker_rate; additionally pixel_flicker_rate of single pixels get a wrong class,
//  - missed instances: with probability miss_rate an instance mask disappears (label 0, id 0),
//  - merged neighbours: each pair of instances touching in the image is merged (one id and
//    the class of the first) with probability merge_rate,
//  - borders: with probability border_rate an instance mask is eroded or dilated (50/50) by
//    1..border_px pixels; eroded pixels become unlabelled (0, 0).
// Decisions are a pure function of (seed, instance id), so the same seed gives the same output
// and an instance's fate does not depend on which other instances are in view.
#include <cstdint>
#include <opencv2/core.hpp>
#include <utility>

#include "semap/core/params.hpp"

namespace semap {

struct SegmentationNoiseParams {
  double flicker_rate = 0.0;        ///< fraction of regions per frame with a wrong class
  double pixel_flicker_rate = 0.0;  ///< fraction of labelled pixels with a wrong class
  double miss_rate = 0.05;          ///< fraction of instances whose mask is dropped per frame
  double merge_rate = 0.05;         ///< probability that two touching instances are merged
  double split_rate = 0.0;          ///< fraction of instances whose mask is split in two per frame
  double border_rate = 0.3;         ///< fraction of instances whose border is eroded/dilated
  int border_px = 2;                ///< maximum erosion/dilation radius (px)
  bool noisy_stuff = true;          ///< flicker also applies to wall/floor/ceiling regions

  void visit(ParamVisitor& v);
  void validate() const;
};

/// Pure and deterministic for (inputs, seed, params). labels CV_8UC1, instances CV_16UC1
/// (same size); throws semap::Error for other types. Returns {noisy labels CV_8UC1, noisy
/// instances CV_16UC1}; the inputs are not modified.
std::pair<cv::Mat, cv::Mat> apply_segmentation_noise(const cv::Mat& labels, const cv::Mat& instances, uint64_t seed,
                                           const SegmentationNoiseParams& params);

}  // namespace semap
