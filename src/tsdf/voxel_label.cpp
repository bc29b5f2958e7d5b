#include "tsdf/voxel_label.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "tsdf/tsdf_interpolation.hpp"

namespace semap {

namespace {

/// The odds by which an argmax must lead the runner-up: a lead of k frames' votes gives r^k; the
/// threshold r^(N - 1/2) lies midway (in log) between N - 1 and N, so the quantised probabilities
/// cannot tip it. Capped at the odds the floor can hold.
float min_lead_odds(const TsdfMap& map) {
  const int min_frames = map.config().mesh_min_label_frames;
  return min_frames == 0 ? 0.0f
                         : static_cast<float>(std::min(std::pow(map.config().bayes_frame_odds(), min_frames - 0.5),
                                                       0.9 * map.bayes().max_odds()));
}

/// Calls visit(i, block, li) for each point whose voxel was observed (TBB; the map must not
/// change meanwhile).
template <class Visit>
void for_each_observed_voxel(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points, Visit&& visit) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    CachedVoxelLookup lookup(map);
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const Block* block = nullptr;
      int li = 0;
      if (lookup.observed(map.voxel_of_point(points[i]), &block, &li)) visit(i, *block, li);
    }
  });
}

}  // namespace

VoxelLabelRule::VoxelLabelRule(const TsdfMap& map)
    : map_(map),
      use_bayes_(map.has_bayes_layer()),
      bayes_stride_(map.bayes().bytes_per_voxel()),
      min_votes_(map.config().mesh_min_label_votes),
      max_bayes_q_(map.bayes().encode(static_cast<float>(map.config().mesh_min_label_probability))),
      min_odds_(min_lead_odds(map)) {}

ClassId VoxelLabelRule::label(const Block& block, int li) const {
  if (use_bayes_) {
    const uint8_t* bayes = &block.bayes[static_cast<size_t>(li) * bayes_stride_];
    return bayes[1] <= max_bayes_q_ && map_.bayes().top_odds(bayes) >= min_odds_ ? BayesLayerCodec::argmax(bayes) : 0;
  }
  return (block.label_confidence && block.label_confidence[li] >= min_votes_) ? block.voxels[li].label : 0;
}

SurfaceLabelEvidence::SurfaceLabelEvidence(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points)
    : codec_(map.bayes()),
      stride_(map.bayes().bytes_per_voxel()),
      min_probability_(static_cast<float>(map.config().mesh_min_label_probability)),
      min_odds_(min_lead_odds(map)) {
  if (!map.has_bayes_layer()) return;
  bytes_.assign(points.size() * stride_, 0);  // all zero = never labelled
  for_each_observed_voxel(map, points, [&](size_t i, const Block& block, int li) {
    std::copy_n(&block.bayes[static_cast<size_t>(li) * stride_], stride_, &bytes_[i * stride_]);
  });
}

ClassId SurfaceLabelEvidence::label_excluding(size_t i, const std::array<bool, kNumClasses>& ruled_out) const {
  if (i >= size()) return 0;
  const ClassDistribution d = codec_.read(&bytes_[i * stride_]);
  if (d.count == 0) return 0;
  // The remaining classes' mass normalises the posterior conditioned on the ruled-out ones.
  int unlisted_remaining = kNumRealClasses - d.count;
  for (int c = 1; c < kNumClasses; ++c)
    if (ruled_out[c] && std::find(d.classes.begin(), d.classes.begin() + d.count, ClassId(c)) == d.classes.begin() + d.count)
      --unlisted_remaining;
  float remaining = d.rest_each * static_cast<float>(std::max(unlisted_remaining, 0));
  ClassId best = 0;
  float best_p = 0.0f, second_p = unlisted_remaining > 0 ? d.rest_each : 0.0f;
  for (int k = 0; k < d.count; ++k) {  // listed in decreasing probability
    if (ruled_out[d.classes[k]]) continue;
    remaining += d.probabilities[k];
    if (best == 0) {
      best = d.classes[k];
      best_p = d.probabilities[k];
    } else {
      second_p = std::max(second_p, d.probabilities[k]);
    }
  }
  if (best == 0 || remaining <= 0.0f || best_p < min_probability_ * remaining) return 0;
  return second_p <= 0.0f || best_p >= min_odds_ * second_p ? best : 0;
}

ClassId SurfaceLabelEvidence::likely_excluding(size_t i, const std::array<bool, kNumClasses>& ruled_out,
                                               const std::array<float, kNumClasses>& scene_prior,
                                               float min_probability) const {
  if (i >= size()) return 0;
  const ClassDistribution d = codec_.read(&bytes_[i * stride_]);
  if (d.count == 0) return 0;
  // p(c | evidence) * prior(c); the classes the voxel's evidence does not list share rest_each,
  // count in the sum and as runner-up, but never win: a guess names a class the network saw there.
  std::array<float, kNumClasses> p;
  p.fill(d.rest_each);
  std::array<bool, kNumClasses> listed{};
  for (int k = 0; k < d.count; ++k) p[d.classes[k]] = d.probabilities[k], listed[d.classes[k]] = true;
  ClassId best = 0;
  float total = 0.0f, best_w = 0.0f, second_w = 0.0f;
  for (int c = 1; c < kNumClasses; ++c) {
    if (ruled_out[c]) continue;
    const float w = p[c] * scene_prior[c];
    total += w;
    if (listed[c] && w > best_w) second_w = std::max(second_w, best_w), best_w = w, best = ClassId(c);
    else second_w = std::max(second_w, w);
  }
  return best != 0 && best_w > second_w && best_w >= min_probability * total ? best : 0;
}

std::vector<ClassId> surface_labels(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points) {
  std::vector<ClassId> out(points.size(), 0);
  if (!map.has_bayes_layer() && !map.has_label_layer()) return out;
  const VoxelLabelRule rule(map);
  for_each_observed_voxel(map, points, [&](size_t i, const Block& block, int li) { out[i] = rule.label(block, li); });
  return out;
}

}  // namespace semap
