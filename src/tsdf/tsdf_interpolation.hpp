#pragma once
// Reading the TSDF between voxel centres: trilinear sdf and its gradient (map merging's
// resampling, projecting points onto the fused surface).
#include <Eigen/Core>

#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

/// Voxel lookups that remember the last block (neighbouring lookups mostly hit the same one).
/// One per thread.
class CachedVoxelLookup {
 public:
  explicit CachedVoxelLookup(const TsdfMap& map) : map_(map) {}
  const TsdfMap& map() const { return map_; }
  /// The voxel if observed (weight > 0), else nullptr; its block and index within it.
  const TsdfVoxel* observed(const VoxelIndex& v, const Block** block_out = nullptr, int* li_out = nullptr) {
    const BlockIndex b = block_of_voxel(v);
    if (!cached_ || b != index_) {
      block_ = map_.find_block(b);
      index_ = b;
      cached_ = true;
    }
    if (!block_) return nullptr;
    const int li = local_index(v);
    const TsdfVoxel* voxel = &block_->voxels[li];
    if (voxel->weight_q == 0) return nullptr;
    if (block_out) *block_out = block_;
    if (li_out) *li_out = li;
    return voxel;
  }

 private:
  const TsdfMap& map_;
  const Block* block_ = nullptr;
  BlockIndex index_{0, 0, 0};
  bool cached_ = false;
};

/// The sdf at `q` (metres, map frame) interpolated trilinearly from the 8 voxel centres around
/// it, and (when asked) its gradient; false when one of the 8 is unobserved.
bool interpolate_sdf(CachedVoxelLookup& lookup, const Eigen::Vector3f& q, float& sdf,
                     Eigen::Vector3f* gradient = nullptr);

/// Each point moved onto the fused surface (the sdf's zero level) along the sdf gradient, a
/// few Newton steps: single-frame back-projections carry the sensor's depth noise, the TSDF is
/// the estimate of the surface from every frame (METHODS B3, B6). A point where the sdf cannot
/// be interpolated, which lies within a quarter voxel of the surface already, or which would
/// move farther than the truncation distance, stays where it is.
/// Parallel (TBB); the map must not change meanwhile.
std::vector<Eigen::Vector3f> project_onto_surface(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points);

}  // namespace semap
