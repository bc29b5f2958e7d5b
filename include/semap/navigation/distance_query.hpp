#pragma once
// 3D distance queries over the TSDF (issue 39), world frame, metres.
//
// The TSDF stores the signed distance to the nearest surface only within its truncation band
// (tsdf.truncation_voxels * voxel_size) and only where blocks were allocated (near observed
// surfaces). So:
//   distance_m(p): the trilinearly interpolated sdf at p (positive in front of surfaces,
//     negative behind), clamped at the truncation distance; NaN where any of the 8 voxels
//     around p is unobserved (unknown space).
//   is_free(p, radius): every voxel whose centre lies within radius + one voxel of p is
//     observed and in front of every surface (sdf > 0). Unobserved voxels count as not free:
//     the answer is conservative (a sphere in open space beyond the band reads not free).
#include <Eigen/Core>

#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

/// Thread safety: const methods read the map only; the map must not change during a call.
class DistanceQuery {
 public:
  explicit DistanceQuery(const TsdfMap& map) : map_(map) {}
  double distance_m(const Eigen::Vector3d& p_W) const;
  bool is_free(const Eigen::Vector3d& p_W, double radius_m) const;
  /// The truncation distance: |distance_m| never exceeds it.
  double truncation_m() const;

 private:
  const TsdfMap& map_;
};

}  // namespace semap
