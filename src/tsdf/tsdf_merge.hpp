#pragma once
// Fusing one saved TSDF into another of the same place (map merging, issue 19): the second map's
// measurements are resampled into the first's voxel grid through the rigid transform that
// aligns them, and fused as one more observation (METHODS.md B6 for sdf and colour, A6 for the
// Bayesian layer).
#include <cstddef>
#include <string>

#include "semap/core/pose.hpp"
#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

struct TsdfMergeStats {
  size_t source_blocks = 0;    ///< blocks of the map fused in
  size_t target_blocks = 0;    ///< blocks of the result that received measurements ...
  size_t allocated_blocks = 0; ///< ... of which new
  size_t voxels_fused = 0;     ///< voxels that received a measurement
};

/// Throws semap::Error naming `what` unless the two maps store voxels alike (voxel size,
/// truncation, weights, layers): a voxel of one is then a measurement the other can fuse.
void require_same_voxel_layout(const TsdfConfig& a, const TsdfConfig& b, const std::string& what);

/// Fuses `source` into `target`. Every voxel of `target`'s grid whose centre, mapped by
/// T_source_target = T_target_source^-1 into the source map, lies among observed source voxels
/// takes the source's value there as one more observation with the source's weight: the sdf
/// trilinearly interpolated (nearest voxel where a neighbour is unobserved), colour and labels
/// of the nearest voxel. sdf and colour: weighted means (B6), the weights added (capped at
/// W_max). Compact labels: the two Boyer-Moore majority summaries combined. Bayesian layer:
/// posterior of both = target x source, normalised (both started from the uniform prior, A6).
/// Each target voxel is fused at most once. Blocks that receive measurements are marked for
/// re-meshing. Parallel over target blocks (TBB).
TsdfMergeStats merge_tsdf(TsdfMap& target, const TsdfMap& source, const Pose& T_target_source);

}  // namespace semap
