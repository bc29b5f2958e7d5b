#include "segmentation/panoptic_segmenter.hpp"

#include <algorithm>
#include <chrono>

#include "semap/core/error.hpp"
#include "segmentation/segmentation_utils.hpp"

namespace semap {
namespace {

/// What an instance writes into each of its pixels.
struct InstancePixel {
  bool valid = false;
  ClassId label = 0;
  float score = 0.f;
  std::vector<float> probabilities;  ///< kNumClasses, only when the semantic result has them
};

std::vector<InstancePixel> instance_table(const SegmentationResult& instances, bool with_probabilities,
                                          double min_score) {
  uint16_t max_id = 0;
  for (const InstanceDetection& d : instances.instances) max_id = std::max(max_id, d.id);
  std::vector<InstancePixel> table(size_t(max_id) + 1);
  for (const InstanceDetection& d : instances.instances) {
    InstancePixel& t = table[d.id];
    t.valid = d.id != 0 && d.class_id != 0 && d.class_id < kNumClasses && d.score >= min_score;
    t.label = d.class_id;
    t.score = std::clamp(d.score, 0.f, 1.f);
    if (!with_probabilities || !t.valid) continue;
    // Label-only observation (METHODS A6, uniform errors): its score on its class, the rest
    // spread over the other real classes; never below the rest, so the argmax is the instance's.
    const float rest = (1.f - t.score) / float(kNumClasses - 2);
    t.probabilities.assign(kNumClasses, rest);
    t.probabilities[0] = 0.f;
    t.probabilities[t.label] = std::max(t.score, rest);
  }
  return table;
}

cv::Size result_size(const SegmentationResult& semantic, const SegmentationResult& instances) {
  if (!semantic.labels.empty()) return semantic.labels.size();
  if (!instances.instance_ids.empty()) return instances.instance_ids.size();
  if (!instances.labels.empty()) return instances.labels.size();
  for (const InstanceDetection& d : instances.instances)
    if (!d.mask.empty()) return d.mask.size();
  return {};
}

cv::Mat instance_id_image(const SegmentationResult& instances, cv::Size size) {
  if (!instances.instance_ids.empty() || instances.instances.empty()) return instances.instance_ids;
  SegmentationResult painted;
  painted.instances = instances.instances;
  paint_instances(painted, size);
  return painted.instance_ids;
}

}  // namespace

SegmentationResult combine_panoptic(SegmentationResult&& semantic, const SegmentationResult& instances,
                                    double min_instance_score) {
  SegmentationResult out = std::move(semantic);
  out.instances = instances.instances;
  const cv::Size size = result_size(out, instances);
  if (size.empty()) return out;
  if (out.labels.empty()) out.labels = cv::Mat::zeros(size, CV_8UC1);
  const cv::Mat ids = instance_id_image(instances, size);
  if (ids.empty()) return out;
  if (ids.size() != size || ids.type() != CV_16UC1)
    throw Error("panoptic segmenter", "instance ids " + std::to_string(ids.cols) + "x" + std::to_string(ids.rows) +
                                          " do not match the semantic labels " + std::to_string(size.width) + "x" +
                                          std::to_string(size.height));
  out.instance_ids = ids.clone();
  const bool has_conf = !out.confidence.empty(), has_probs = !out.probabilities.empty();
  const std::vector<InstancePixel> table = instance_table(instances, has_probs, min_instance_score);
  const int nc = has_probs ? out.probabilities.channels() : 0;
  for (int y = 0; y < size.height; ++y) {
    uint16_t* id = out.instance_ids.ptr<uint16_t>(y);
    uint8_t* label = out.labels.ptr<uint8_t>(y);
    float* conf = has_conf ? out.confidence.ptr<float>(y) : nullptr;
    float* probs = has_probs ? out.probabilities.ptr<float>(y) : nullptr;
    for (int x = 0; x < size.width; ++x) {
      if (id[x] == 0) continue;
      const InstancePixel* t = id[x] < table.size() && table[id[x]].valid ? &table[id[x]] : nullptr;
      if (!t) {
        id[x] = 0;  // a weak (or unknown) instance leaves the semantic pixel as it was
        continue;
      }
      label[x] = t->label;
      if (conf) conf[x] = t->score;
      if (probs) std::copy_n(t->probabilities.data(), std::min(nc, kNumClasses), probs + size_t(x) * nc);
    }
  }
  return out;
}

PanopticSegmenter::PanopticSegmenter(std::unique_ptr<Segmenter> semantic, std::unique_ptr<Segmenter> instance,
                                     double min_instance_score)
    : semantic_(std::move(semantic)), instance_(std::move(instance)), min_instance_score_(min_instance_score) {
  if (!semantic_ || !instance_) throw Error("panoptic segmenter", "needs a semantic and an instance segmenter");
}

SegmentationResult PanopticSegmenter::segment(const Frame& frame) {
  using Clock = std::chrono::steady_clock;
  const auto ms = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  };
  const auto t0 = Clock::now();
  SegmentationResult sem = semantic_->segment(frame);
  const auto t1 = Clock::now();
  const SegmentationResult inst = instance_->segment(frame);
  const auto t2 = Clock::now();
  SegmentationResult out = combine_panoptic(std::move(sem), inst, min_instance_score_);
  const auto t3 = Clock::now();
  timing_ = {ms(t0, t1), ms(t1, t2), ms(t2, t3)};
  out.frame_index = frame.index;
  out.timestamp = frame.timestamp;
  return out;
}

std::string PanopticSegmenter::name() const { return "panoptic:" + semantic_->name() + "+" + instance_->name(); }

}  // namespace semap
