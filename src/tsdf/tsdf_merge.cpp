#include "tsdf/tsdf_merge.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_set>
#include <vector>

#include "semap/core/error.hpp"
#include "tsdf/tsdf_interpolation.hpp"

namespace semap {
namespace {

/// One source measurement resampled at a target voxel centre.
struct Sample {
  bool valid = false;
  float sdf = 0.0f, weight = 0.0f;
  const TsdfVoxel* nearest = nullptr;  ///< for the labels
  const Block* nearest_block = nullptr;
  int nearest_li = 0;
};

struct BlockSamples {
  BlockIndex index;
  std::vector<Sample> voxels;  ///< kBlockVoxels, or empty when no voxel got a measurement
};

/// The source's measurement at `q` (source frame, metres): trilinear sdf where the 8 voxel
/// centres around q are observed, else the nearest voxel's; the nearest voxel's weight.
Sample sample_at(CachedVoxelLookup& lookup, const TsdfMap& source, const Eigen::Vector3f& q) {
  Sample s;
  s.nearest = lookup.observed(source.voxel_of_point(q), &s.nearest_block, &s.nearest_li);
  if (!s.nearest) return s;
  s.valid = true;
  s.weight = source.weights().decode(s.nearest->weight_q);
  if (!interpolate_sdf(lookup, q, s.sdf)) s.sdf = s.nearest->sdf();  // a neighbour unobserved
  return s;
}

/// Target blocks the source's blocks can reach through the transform (their boxes' corners).
std::vector<BlockIndex> reachable_blocks(const TsdfMap& target, const TsdfMap& source, const Pose& T_target_source) {
  std::unordered_set<BlockIndex, BlockHash> out;
  const Eigen::Isometry3f T = T_target_source.cast<float>();
  const float side = source.block_size(), target_side = target.block_size();
  for (const auto& block : source.blocks()) {
    Eigen::AlignedBox3f box;
    const Eigen::Vector3f origin = block->index.cast<float>() * side;
    for (int c = 0; c < 8; ++c) box.extend(T * (origin + side * Eigen::Vector3f(c & 1, (c >> 1) & 1, (c >> 2) & 1)));
    const Eigen::Vector3i lo = (box.min() / target_side).array().floor().cast<int>();
    const Eigen::Vector3i hi = (box.max() / target_side).array().floor().cast<int>();
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) out.insert({x, y, z});
  }
  std::vector<BlockIndex> sorted(out.begin(), out.end());
  std::sort(sorted.begin(), sorted.end(), [](const BlockIndex& a, const BlockIndex& b) {
    return std::tie(a.z(), a.y(), a.x()) < std::tie(b.z(), b.y(), b.x());
  });
  return sorted;
}

BlockSamples sample_block(const TsdfMap& target, const TsdfMap& source, const Eigen::Isometry3f& T_source_target,
                          const BlockIndex& index) {
  BlockSamples out{index, {}};
  CachedVoxelLookup lookup(source);
  std::vector<Sample> voxels(kBlockVoxels);
  bool any = false;
  const VoxelIndex first = index * kBlockSide;
  for (int li = 0; li < kBlockVoxels; ++li) {
    const VoxelIndex v = first + VoxelIndex(li & 7, (li >> 3) & 7, li >> 6);
    voxels[li] = sample_at(lookup, source, T_source_target * target.voxel_centre(v));
    any |= voxels[li].valid;
  }
  if (any) out.voxels = std::move(voxels);
  return out;
}

/// Two Boyer-Moore majority summaries (label, votes) as one: the label of the larger count
/// keeps the difference (the same label: the sum).
void combine_votes(ClassId& label, uint8_t& votes, ClassId other_label, uint8_t other_votes) {
  if (other_label == 0 || other_votes == 0) return;
  if (votes == 0 || label == other_label) {
    votes = static_cast<uint8_t>(std::min(255, (label == other_label ? votes : 0) + other_votes));
    label = other_label;
  } else if (votes >= other_votes) {
    votes = static_cast<uint8_t>(votes - other_votes);
  } else {
    votes = static_cast<uint8_t>(other_votes - votes);
    label = other_label;
  }
}

void fuse_sample(TsdfMap& target, const TsdfMap& source, Block& block, int li, const Sample& s) {
  TsdfVoxel& v = block.voxels[li];
  const float W = target.weights().decode(v.weight_q);
  const float W_new = W + s.weight;
  v.set_sdf(W > 0 ? (W * v.sdf() + s.weight * s.sdf) / W_new : s.sdf);
  v.weight_q = target.weights().encode(std::min(W_new, static_cast<float>(target.config().weight_max)));
  if (target.has_colour_layer()) {
    Rgb8& c = block.colour[li];
    const Rgb8& o = s.nearest_block->colour[s.nearest_li];
    const float a = W / W_new, b = s.weight / W_new;
    c = Rgb8{static_cast<uint8_t>(a * c.r + b * o.r + 0.5f), static_cast<uint8_t>(a * c.g + b * o.g + 0.5f),
             static_cast<uint8_t>(a * c.b + b * o.b + 0.5f)};
  }
  if (target.has_label_layer())
    combine_votes(v.label, block.label_confidence[li], s.nearest->label, s.nearest_block->label_confidence[s.nearest_li]);
  if (target.has_bayes_layer()) {
    const size_t stride = static_cast<size_t>(target.bayes().bytes_per_voxel());
    const ClassDistribution observed = source.bayes().read(&s.nearest_block->bayes[s.nearest_li * stride]);
    if (observed.count > 0) target.bayes().update(&block.bayes[li * stride], observed);
  }
}

}  // namespace

void require_same_voxel_layout(const TsdfConfig& a, const TsdfConfig& b, const std::string& what) {
  auto differs = [&](const char* key, double x, double y) {
    if (x != y)
      throw Error(what, std::string("the maps store voxels differently: tsdf.") + key + " " + compact_number(x) +
                            " vs " + compact_number(y) + " (merge maps made with the same tsdf settings)");
  };
  differs("voxel_size", a.voxel_size, b.voxel_size);
  differs("truncation_voxels", a.truncation_voxels, b.truncation_voxels);
  differs("weight_unit", a.weight_unit, b.weight_unit);
  differs("weight_max", a.weight_max, b.weight_max);
  differs("label_layer", a.label_layer, b.label_layer);
  differs("bayes_layer", a.bayes_layer, b.bayes_layer);
  differs("bayes_top_k", a.bayes_top_k, b.bayes_top_k);
  differs("bayes_min_probability", a.bayes_min_probability, b.bayes_min_probability);
  differs("colour_layer", a.colour_layer, b.colour_layer);
}

TsdfMergeStats merge_tsdf(TsdfMap& target, const TsdfMap& source, const Pose& T_target_source) {
  require_same_voxel_layout(target.config(), source.config(), "merge_tsdf");
  TsdfMergeStats stats;
  stats.source_blocks = source.num_blocks();
  const std::vector<BlockIndex> candidates = reachable_blocks(target, source, T_target_source);
  const Eigen::Isometry3f T_source_target = T_target_source.inverse().cast<float>();
  constexpr size_t kChunk = 1024;  // blocks sampled at a time: bounds the samples held
  for (size_t begin = 0; begin < candidates.size(); begin += kChunk) {
    const size_t end = std::min(candidates.size(), begin + kChunk);
    std::vector<BlockSamples> samples(end - begin);
    tbb::parallel_for(tbb::blocked_range<size_t>(begin, end), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i)
        samples[i - begin] = sample_block(target, source, T_source_target, candidates[i]);
    });
    for (const BlockSamples& block_samples : samples) {
      if (block_samples.voxels.empty()) continue;
      const bool existed = target.find_block(block_samples.index) != nullptr;
      Block& block = target.allocate_block(block_samples.index);
      stats.allocated_blocks += !existed;
      ++stats.target_blocks;
      for (int li = 0; li < kBlockVoxels; ++li) {
        if (!block_samples.voxels[li].valid) continue;
        fuse_sample(target, source, block, li, block_samples.voxels[li]);
        ++stats.voxels_fused;
      }
      block.mesh_dirty = true;
    }
  }
  return stats;
}

}  // namespace semap
