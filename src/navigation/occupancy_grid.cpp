#include "semap/navigation/occupancy_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "tsdf/voxel_label.hpp"

namespace semap {
namespace {

/// A surface voxel in the gravity frame.
struct SurfaceSample {
  Eigen::Vector2d xy_G;
  float z_m;
  ClassId label;
};

/// Observed voxels within one voxel of the surface (|sdf| < s), in the gravity frame.
std::vector<SurfaceSample> surface_samples(const TsdfMap& map, const Pose& T_W_G) {
  const Pose T_G_W = T_W_G.inverse();
  const Eigen::Matrix3d R = T_G_W.rotation();
  const Eigen::Vector3d t = T_G_W.translation();
  const VoxelLabelRule labels(map);
  const float s = map.voxel_size();
  std::vector<SurfaceSample> out;
  for (const Block* block : map.sorted_blocks()) {
    const VoxelIndex base = block->index * kBlockSide;
    for (int li = 0; li < kBlockVoxels; ++li) {
      const TsdfVoxel& v = block->voxels[li];
      if (v.weight_q == 0 || !(std::abs(v.sdf()) < s)) continue;
      const VoxelIndex vi = base + VoxelIndex(li & 7, (li >> 3) & 7, li >> 6);
      const Eigen::Vector3d p_G = R * map.voxel_centre(vi).cast<double>() + t;
      out.push_back({p_G.head<2>(), static_cast<float>(p_G.z()), labels.label(*block, li)});
    }
  }
  return out;
}

}  // namespace

CellState OccupancyGrid::state_at_W(const Eigen::Vector3d& p_W) const {
  const Eigen::Vector3d p_G = T_W_G.inverse() * p_W;
  const Eigen::Vector2i c = cell_of(p_G.head<2>());
  return contains(c.x(), c.y()) ? state[index(c.x(), c.y())] : CellState::kUnknown;
}

size_t OccupancyGrid::count(CellState s) const { return std::count(state.begin(), state.end(), s); }

OccupancyGrid build_occupancy_grid(const TsdfMap& map, const Pose& T_W_G, const NavigationConfig& config) {
  config.validate();
  OccupancyGrid grid;
  grid.resolution_m = config.resolution_m;
  grid.T_W_G = T_W_G;
  grid.min_height_m = config.min_height_m;
  grid.max_height_m = config.max_height_m;
  const std::vector<SurfaceSample> samples = surface_samples(map, T_W_G);
  // Extent: every surface sample up to the band's top (the floor and what stands on it).
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const SurfaceSample& s : samples)
    if (s.z_m > -config.min_height_m && s.z_m <= config.max_height_m) lo = lo.cwiseMin(s.xy_G), hi = hi.cwiseMax(s.xy_G);
  if (!(lo.x() <= hi.x())) return grid;  // nothing in or under the band: an empty grid
  const double r = config.resolution_m;
  grid.origin_G = (lo / r).array().floor().matrix() * r;
  grid.width = static_cast<int>(std::floor((hi.x() - grid.origin_G.x()) / r)) + 1;
  grid.height = static_cast<int>(std::floor((hi.y() - grid.origin_G.y()) / r)) + 1;
  const size_t n = static_cast<size_t>(grid.width) * grid.height;
  grid.state.assign(n, CellState::kUnknown);
  grid.top_label.assign(n, 0);
  grid.top_height_m.assign(n, std::numeric_limits<float>::quiet_NaN());
  std::vector<uint8_t> occupied(n, 0), floor(n, 0);
  for (const SurfaceSample& s : samples) {
    if (s.z_m <= -config.min_height_m || s.z_m > config.max_height_m) continue;
    const Eigen::Vector2i c = grid.cell_of(s.xy_G);
    if (!grid.contains(c.x(), c.y())) continue;
    const size_t i = grid.index(c.x(), c.y());
    (s.z_m >= config.min_height_m ? occupied : floor)[i] = 1;
    if (!(s.z_m <= grid.top_height_m[i])) grid.top_height_m[i] = s.z_m, grid.top_label[i] = s.label;
  }
  for (size_t i = 0; i < n; ++i)
    grid.state[i] = occupied[i] ? CellState::kOccupied : floor[i] ? CellState::kFree : CellState::kUnknown;
  return grid;
}

std::vector<float> distance_to_obstacles_m(const OccupancyGrid& grid) {
  const size_t n = grid.state.size();
  if (grid.count(CellState::kOccupied) == 0) return std::vector<float>(n, std::numeric_limits<float>::infinity());
  // distanceTransform: distance to the nearest zero pixel; occupied cells are the zeros.
  cv::Mat not_occupied(grid.height, grid.width, CV_8UC1);
  for (int iy = 0; iy < grid.height; ++iy)
    for (int ix = 0; ix < grid.width; ++ix)
      not_occupied.at<uint8_t>(iy, ix) = grid.state[grid.index(ix, iy)] == CellState::kOccupied ? 0 : 255;
  cv::Mat distance_cells;
  cv::distanceTransform(not_occupied, distance_cells, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  std::vector<float> out(n);
  for (int iy = 0; iy < grid.height; ++iy)
    for (int ix = 0; ix < grid.width; ++ix)
      out[grid.index(ix, iy)] = distance_cells.at<float>(iy, ix) * static_cast<float>(grid.resolution_m);
  return out;
}

}  // namespace semap
