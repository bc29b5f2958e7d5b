#pragma once
// 2D occupancy grid and distance field of a TSDF map in the gravity frame (issue 39).
//
// Frame: the gravity frame G of core/gravity.hpp (z up, z = 0 on the floor plane); the grid
// lies in its x-y plane. Cell (ix, iy) covers x in origin.x + [ix, ix + 1) * resolution and the
// same in y; cells are stored row-major with iy = 0 the lowest y (files flip it: see
// write_navigation_maps).
//
// A TSDF surface voxel (observed, |sdf| < one voxel) at height z:
//   - with min_height_m <= z <= max_height_m makes its cell occupied (an obstacle in the band);
//   - with |z| < min_height_m is floor: its cell is free unless occupied;
// every other cell is unknown. The top label of a cell is the class (VoxelLabelRule) of its
// highest surface voxel at or below max_height_m.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "semap/core/labels.hpp"
#include "semap/core/pose.hpp"
#include "semap/navigation/navigation_config.hpp"
#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

enum class CellState : uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

struct OccupancyGrid {
  int width = 0, height = 0;  ///< cells along x_G, y_G
  double resolution_m = 0.05;
  Eigen::Vector2d origin_G = Eigen::Vector2d::Zero();  ///< (x, y) of the corner of cell (0, 0), gravity frame
  Pose T_W_G = Pose::Identity();                       ///< world from gravity frame
  double min_height_m = 0.0, max_height_m = 0.0;       ///< the band the grid was built with
  std::vector<CellState> state;                        ///< width * height, row-major, iy = 0 lowest y
  std::vector<ClassId> top_label;                      ///< class of the top-most surface (0: none / unlabelled)
  std::vector<float> top_height_m;                     ///< its height above the floor (NaN: no surface)

  size_t index(int ix, int iy) const { return static_cast<size_t>(iy) * width + ix; }
  bool contains(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width && iy < height; }
  /// Cell of a gravity-frame point's (x, y) (may lie outside: check contains()).
  Eigen::Vector2i cell_of(const Eigen::Vector2d& xy_G) const {
    return ((xy_G - origin_G) / resolution_m).array().floor().cast<int>();
  }
  Eigen::Vector2d cell_centre(int ix, int iy) const {
    return origin_G + (Eigen::Vector2d(ix, iy).array() + 0.5).matrix() * resolution_m;
  }
  /// State of the cell under a world point (unknown outside the grid).
  CellState state_at_W(const Eigen::Vector3d& p_W) const;
  size_t count(CellState s) const;
};

/// See the file comment. Parallel-safe: reads the map only (it must not change meanwhile).
OccupancyGrid build_occupancy_grid(const TsdfMap& map, const Pose& T_W_G, const NavigationConfig& config);

/// Euclidean distance (m) from each cell centre to the nearest occupied cell centre, same
/// layout as grid.state; +infinity everywhere when no cell is occupied.
std::vector<float> distance_to_obstacles_m(const OccupancyGrid& grid);

}  // namespace semap
