#pragma once
// The built-in noisy segmenter of `semap demo` / `--seg-noise`: the frame's ground-truth
// labels passed through the synthetic noise model (synth/segmentation_noise.hpp), then
// segmented like ground truth. Lets the whole pipeline run without a network.
#include <memory>

#include "semap/segmentation/segmenter.hpp"
#include "semap/synth/segmentation_noise.hpp"

namespace semap {

class SimulatedSegmenter : public Segmenter {
 public:
  SimulatedSegmenter(std::unique_ptr<Segmenter> ground_truth, const SegmentationNoiseParams& noise, uint64_t seed)
      : ground_truth_(std::move(ground_truth)), noise_(noise), seed_(seed) {}

  SegmentationResult segment(const Frame& frame) override {
    Frame noisy = frame;
    if (frame.has_labels() && frame.has_instances())
      std::tie(noisy.labels, noisy.instances) =
          apply_segmentation_noise(frame.labels, frame.instances, seed_ * 1000003ULL + frame.index, noise_);
    return ground_truth_->segment(noisy);
  }
  std::string name() const override { return "simulated(" + ground_truth_->name() + ")"; }
  bool is_cheap() const override { return true; }

 private:
  std::unique_ptr<Segmenter> ground_truth_;
  SegmentationNoiseParams noise_;
  uint64_t seed_;
};

}  // namespace semap
