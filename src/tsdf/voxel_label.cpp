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

/// The Bayesian bytes of the voxel containing `p`, or, when that voxel was never labelled, of the
/// nearest labelled voxel along the surface normal (the sdf gradient) within `reach` voxels that
/// lies no nearer another surface than this one: a frame labels only the voxels within its label
/// band of its own depth (METHODS A6), and where the fused surface lies farther from the few
/// segmented frames' depths (far, noisy depth seen at a grazing angle) their labels sit a voxel or
/// two off it, in front or behind. A voxel beside another surface (a cup standing on the table)
/// has a sdf, on this surface's side, short of its distance from this one, and is not read. Null: none.
const uint8_t* labelled_along_normal(CachedVoxelLookup& lookup, const Eigen::Vector3f& p, int reach, int stride) {
  const TsdfMap& map = lookup.map();
  const float voxel_m = static_cast<float>(map.config().voxel_size);
  const auto labelled_at = [&](const VoxelIndex& v, const float* expected_sdf) -> const uint8_t* {
    const Block* block = nullptr;
    int li = 0;
    const TsdfVoxel* voxel = lookup.observed(v, &block, &li);
    if (!voxel) return nullptr;
    const uint8_t* bayes = &block->bayes[static_cast<size_t>(li) * stride];
    if (bayes[0] == 0) return nullptr;
    // Nearer another surface than this one: its distance (on this surface's side) falls short.
    if (expected_sdf && std::copysign(1.0f, *expected_sdf) * voxel->sdf() < std::fabs(*expected_sdf) - 0.5f * voxel_m)
      return nullptr;
    return bayes;
  };
  if (const uint8_t* own = labelled_at(map.voxel_of_point(p), nullptr); own || reach <= 0) return own;
  float sdf = 0.0f;
  Eigen::Vector3f gradient;
  if (!interpolate_sdf(lookup, p, sdf, &gradient) || !(gradient.norm() > 1e-6f)) return nullptr;
  const Eigen::Vector3f normal = gradient.normalized();
  for (int k = 1; k <= reach; ++k)
    for (const float side : {1.0f, -1.0f}) {
      const VoxelIndex v = map.voxel_of_point(p + side * float(k) * voxel_m * normal);
      // This surface's distance at the voxel's centre (the sdf grows along the normal).
      const float expected = sdf + normal.dot(map.voxel_centre(v) - p);
      if (const uint8_t* found = labelled_at(v, &expected)) return found;
    }
  return nullptr;
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
  // Never beyond the truncation: no frame's label lands farther from its depth.
  const int reach = static_cast<int>(
      std::floor(std::min(map.config().label_evidence_reach_voxels, map.config().truncation_voxels)));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    CachedVoxelLookup lookup(map);
    for (size_t i = r.begin(); i < r.end(); ++i)
      if (const uint8_t* bayes = labelled_along_normal(lookup, points[i], reach, stride_))
        std::copy_n(bayes, stride_, &bytes_[i * stride_]);
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
