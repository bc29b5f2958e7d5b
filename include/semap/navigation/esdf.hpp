#pragma once
// 3D Euclidean signed distance field of a TSDF map (issue 39; the voxblox/nvblox ESDF idea):
// the distance from any observed point to the nearest observed surface, far beyond the TSDF's
// truncation band, computed once per map and then read per query.
//
// Cells: a regular grid over the observed space's bounding box, cell edge = the TSDF voxel
// size times the smallest integer k that keeps the build within navigation.esdf_max_memory_mb
// (kEsdfBuildBytesPerCell per cell; k = 1 on room-sized maps). Each cell reads the TSDF voxel
// at its centre (METHODS.md B3, B4):
//   free      observed (weight > 0) with sdf > 0, or in a block the camera looked through (below);
//   occupied  observed with sdf <= 0 (the thin observed band behind a surface);
//   unknown   everything else (never seen, or deep inside/behind surfaces): NaN.
// Looked-through space: the projective integrator allocates blocks near surfaces only, so the
// open middle of a room holds no voxels. A block counts as seen free when the segment from a
// camera position (the trajectory, thinned to kCarveCameraSpacingM) to a surface voxel of
// another block (one per block, within tsdf.max_depth) crosses it and crosses no observed
// surface on the way (sdf <= 0 in an allocated block): a line of sight, as voxblox carves free
// space along every ray. So do the blocks on the camera's path (between consecutive positions
// at most 0.5 m apart; a longer step is a jump).
// Without camera positions only the TSDF's own voxels are observed.
//
// Surface: the zero crossings of the sdf between 6-neighbour cells of opposite known state
// (linear interpolation); each cell next to one carries their mean point. A crossing whose sdf
// jumps by more than 3 cell edges is no surface: a voxel in a surface's shadow (negative from
// views where it lay just behind the surface, positive from the others); an occupied cell with
// only such crossings to its free neighbours is taken as free. The nearest such
// cell of every cell is found by an exact separable Euclidean distance transform with nearest
// site tracking (Felzenszwalb & Huttenlocher 2012, three 1D passes), and the distance is then
// measured to that cell's sub-voxel surface point: positive in free cells, negative in occupied
// ones, clamped at navigation.esdf_max_distance_m ("at least that far"). The transform runs
// through unknown cells: a distance is to the nearest *observed* surface (an unobserved
// obstacle may be closer, as in voxblox and nvblox).
#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "semap/navigation/navigation_config.hpp"
#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

/// Build memory per grid cell: state (1 B), nearest site (4 B), squared distance then result
/// (4 B), and room for surface points (16 B each) on up to a quarter of the cells (4 B).
inline constexpr size_t kEsdfBuildBytesPerCell = 13;
/// Camera positions closer than this to an already used one add no lines of sight.
inline constexpr double kCarveCameraSpacingM = 0.2;

struct EsdfStats {
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();  ///< cells per axis
  double cell_m = 0.0;             ///< cell edge
  size_t free_cells = 0, occupied_cells = 0, unknown_cells = 0;
  size_t carved_blocks = 0;        ///< unallocated TSDF blocks seen free along lines of sight or the path
  size_t surface_cells = 0;        ///< cells next to a zero crossing (the transform's sites)
  size_t shadow_cells = 0;         ///< occupied cells turned free: only implausible crossings (esdf.cpp)
  size_t cameras_used = 0;         ///< camera positions after thinning
  size_t lines_of_sight = 0, blocked_lines = 0;
  double build_s = 0.0;            ///< wall time of build_esdf
  size_t peak_bytes = 0;           ///< grid memory during the build (kEsdfBuildBytesPerCell per cell)
};

/// Immutable after build_esdf. Thread safety: every method is const and may run concurrently.
class Esdf {
 public:
  Esdf() = default;
  /// Signed distance (m) at a world point: trilinear between the 8 cell centres around it; NaN
  /// when any of them is unknown or outside the grid. |d| <= max_distance_m().
  double distance_m(const Eigen::Vector3d& p_W) const;
  /// The distance stored for a cell (NaN: unknown); `cell` in grid coordinates 0..dims-1.
  float cell_distance_m(const Eigen::Vector3i& cell) const { return distance_[linear(cell)]; }
  Eigen::Vector3d cell_centre_W(const Eigen::Vector3i& cell) const {
    return ((origin_cell_ + cell).cast<double>().array() + 0.5).matrix() * cell_m_;
  }
  const Eigen::Vector3i& dims() const { return dims_; }
  double max_distance_m() const { return max_distance_m_; }
  const EsdfStats& stats() const { return stats_; }
  /// Memory held after the build (the distance per cell).
  size_t memory_bytes() const { return distance_.size() * sizeof(float); }

 private:
  friend Esdf build_esdf(const TsdfMap&, std::span<const Eigen::Vector3d>, const NavigationConfig&);
  size_t linear(const Eigen::Vector3i& c) const {
    return static_cast<size_t>(c.x()) + static_cast<size_t>(dims_.x()) * (c.y() + static_cast<size_t>(dims_.y()) * c.z());
  }
  Eigen::Vector3i origin_cell_ = Eigen::Vector3i::Zero();  ///< global index of cell (0, 0, 0) at cell_m_
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  double cell_m_ = 0.0, max_distance_m_ = 0.0;
  std::vector<float> distance_;
  EsdfStats stats_;
};

/// Builds the field of `map` (see the file comment). `camera_positions_W`: where the camera
/// was (the trajectory's translations); empty: no looked-through space. Parallel (TBB); the map
/// must not change meanwhile. Throws semap::Error("esdf", ...) when even the coarsest grid
/// (k up to 16) exceeds navigation.esdf_max_memory_mb.
Esdf build_esdf(const TsdfMap& map, std::span<const Eigen::Vector3d> camera_positions_W, const NavigationConfig& config);

}  // namespace semap
