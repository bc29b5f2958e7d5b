#include "tsdf/voxel_label.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "tsdf/tsdf_interpolation.hpp"

namespace semap {

VoxelLabelRule::VoxelLabelRule(const TsdfMap& map)
    : map_(map),
      use_bayes_(map.has_bayes_layer()),
      bayes_stride_(map.bayes().bytes_per_voxel()),
      min_votes_(map.config().mesh_min_label_votes),
      max_bayes_q_(map.bayes().encode(static_cast<float>(map.config().mesh_min_label_probability))) {
  // The argmax must lead the runner-up by N frames' votes. The odds of a lead of k frames are
  // r^k; the threshold r^(N - 1/2) lies midway (in log) between N - 1 and N, so the quantised
  // probabilities cannot tip it. Capped at the odds the floor can hold.
  const int min_frames = map.config().mesh_min_label_frames;
  min_odds_ = min_frames == 0 ? 0.0f
                              : static_cast<float>(std::min(std::pow(map.config().bayes_frame_odds(), min_frames - 0.5),
                                                            0.9 * map.bayes().max_odds()));
}

ClassId VoxelLabelRule::label(const Block& block, int li) const {
  if (use_bayes_) {
    const uint8_t* bayes = &block.bayes[static_cast<size_t>(li) * bayes_stride_];
    return bayes[1] <= max_bayes_q_ && map_.bayes().top_odds(bayes) >= min_odds_ ? BayesLayerCodec::argmax(bayes) : 0;
  }
  return (block.label_confidence && block.label_confidence[li] >= min_votes_) ? block.voxels[li].label : 0;
}

std::vector<ClassId> surface_labels(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points) {
  std::vector<ClassId> out(points.size(), 0);
  if (!map.has_bayes_layer() && !map.has_label_layer()) return out;
  const VoxelLabelRule rule(map);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    CachedVoxelLookup lookup(map);
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const Block* block = nullptr;
      int li = 0;
      if (lookup.observed(map.voxel_of_point(points[i]), &block, &li)) out[i] = rule.label(*block, li);
    }
  });
  return out;
}

}  // namespace semap
