#include "semap/navigation/distance_query.hpp"

#include <cmath>
#include <limits>

#include "tsdf/tsdf_interpolation.hpp"

namespace semap {

double DistanceQuery::truncation_m() const { return map_.config().truncation_voxels * map_.voxel_size(); }

double DistanceQuery::distance_m(const Eigen::Vector3d& p_W) const {
  CachedVoxelLookup lookup(map_);
  float sdf = 0.f;
  if (!interpolate_sdf(lookup, p_W.cast<float>(), sdf)) return std::numeric_limits<double>::quiet_NaN();
  return std::clamp(static_cast<double>(sdf), -truncation_m(), truncation_m());
}

bool DistanceQuery::is_free(const Eigen::Vector3d& p_W, double radius_m) const {
  if (!(radius_m >= 0.0) || !p_W.allFinite()) return false;
  const double s = map_.voxel_size();
  const double reach = radius_m + s;
  if (reach / s > 512) return false;  // a query this large is never answered voxel by voxel
  const Eigen::Vector3f p = p_W.cast<float>();
  const VoxelIndex lo = map_.voxel_of_point(p - Eigen::Vector3f::Constant(static_cast<float>(reach)));
  const VoxelIndex hi = map_.voxel_of_point(p + Eigen::Vector3f::Constant(static_cast<float>(reach)));
  CachedVoxelLookup lookup(map_);
  const float reach2 = static_cast<float>(reach * reach);
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const VoxelIndex v(x, y, z);
        if ((map_.voxel_centre(v) - p).squaredNorm() > reach2) continue;
        const TsdfVoxel* voxel = lookup.observed(v);
        if (!voxel || !(voxel->sdf() > 0.f)) return false;
      }
  return true;
}

}  // namespace semap
