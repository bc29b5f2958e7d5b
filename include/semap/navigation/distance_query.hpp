#pragma once
// 3D distance queries over a TSDF map (issue 39), world frame, metres, answered from a 3D
// Euclidean signed distance field built once at construction (navigation/esdf.hpp):
//   distance_m(p): signed Euclidean distance from p to the nearest observed surface: positive
//     in observed free space, negative in the observed band behind a surface, NaN where p is
//     unobserved (never seen, or deep inside an object or behind a wall). Not limited to the
//     TSDF's truncation band: |d| reaches navigation.esdf_max_distance_m (2 m), and a value of
//     that size means "at least that far".
//   is_free(p, r): p is observed and distance_m(p) >= r: the ball of radius r around p holds no
//     observed surface. A radius above esdf_max_distance_m is never free (the field does not
//     know), nor is a point of unknown space.
// With the camera positions the field also covers the open space the camera looked through
// (the middle of a room, where the TSDF holds no voxels); without them only the TSDF's observed
// voxels (a band of a block or so around the surfaces).
#include <Eigen/Core>
#include <span>

#include "semap/navigation/esdf.hpp"
#include "semap/navigation/navigation_config.hpp"
#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

/// Thread safety: construction reads the map (it must not change meanwhile); afterwards every
/// method is const, independent of the map, and may run concurrently.
class DistanceQuery {
 public:
  explicit DistanceQuery(const TsdfMap& map, const NavigationConfig& config = {},
                         std::span<const Eigen::Vector3d> camera_positions_W = {})
      : esdf_(build_esdf(map, camera_positions_W, config)) {}
  double distance_m(const Eigen::Vector3d& p_W) const { return esdf_.distance_m(p_W); }
  bool is_free(const Eigen::Vector3d& p_W, double radius_m) const;
  /// The largest distance reported (navigation.esdf_max_distance_m).
  double max_distance_m() const { return esdf_.max_distance_m(); }
  const Esdf& esdf() const { return esdf_; }

 private:
  Esdf esdf_;
};

}  // namespace semap
