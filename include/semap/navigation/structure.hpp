#pragma once
// Structural surfaces of a map in the gravity frame G (issue 39; core/gravity.hpp: z up, z = 0
// on the floor plane): the floor, the walls and the ceiling, scene-graph nodes next to the
// objects. The mesh's triangle normals, as wound, point into observed free space (the TSDF
// mesher's convention), so a wall's normal points into the room it bounds.
//
// Floor: z = 0 by the definition of G; its area is the grid's free area (build_scene_graph).
// Walls: candidate triangles have a normal within vertical_tolerance_deg of horizontal and a
//   structural class or none (wall, door, window, curtain, mirror, picture, unlabelled: a table's
//   or a cabinet's side is no wall). Greedy plane extraction, largest first:
//   1. the peak of the candidates' area-weighted azimuth histogram (5 deg bins, a bin and its
//      two neighbours);
//   2. among candidates within vertical_tolerance_deg of that azimuth, the peak of their offset
//      histogram (n . p, bins of wall_plane_tolerance_m, a bin and its two neighbours);
//   3. inliers (within the azimuth tolerance and wall_plane_tolerance_m of the plane), refit once
//      as the area-weighted mean normal and offset, inliers taken again;
//   4. a wall when the inliers hold wall_min_area_m2 and either at least half of that area is
//      labelled wall (the segmenter says so; a camera looking down at a kitchen maps a wall's
//      lower part only) or they reach wall_min_top_m (98th percentile of their heights,
//      area-weighted: geometry alone, furniture stays lower); the inliers leave the candidates
//      either way.
//   Stops when the azimuth peak holds under wall_min_area_m2. The wall's extent along the plane
//   is the 2nd..98th area-weighted percentile of its inliers' positions (a segment in x-y).
// Ceiling: triangles facing down (normal within vertical_tolerance_deg of -z), at least
//   ceiling_min_height_m high, of class ceiling or none; the densest height (bin pair of 4 cm)
//   holding wall_min_area_m2 is the ceiling, at the area-weighted median height there. "Mapped"
//   means that much area was seen: a run that never looked up has no ceiling node.
#include <Eigen/Core>
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "semap/core/params.hpp"
#include "semap/core/point_cloud.hpp"
#include "semap/core/pose.hpp"
#include "semap/navigation/navigation_config.hpp"

namespace semap {

enum class SurfaceKind : uint8_t { kFloor, kWall, kCeiling };
inline constexpr EnumNames<SurfaceKind, 3> kSurfaceKindNames{
    {{SurfaceKind::kFloor, "floor"}, {SurfaceKind::kWall, "wall"}, {SurfaceKind::kCeiling, "ceiling"}}};

struct SurfaceNode {
  std::string id;  ///< "floor", "wall_<k>", "ceiling"
  SurfaceKind kind = SurfaceKind::kFloor;
  double height_m = 0.0;  ///< floor and ceiling: height in G; walls: their top (98th percentile)
  double area_m2 = 0.0;   ///< observed area (floor: the free cells of the grid)
  // Walls only: the vertical plane normal_G . (x, y) = offset_m, seen over segment_G and
  // bottom_m..height_m.
  Eigen::Vector2d normal_G = Eigen::Vector2d::Zero();  ///< unit, horizontal, into the room
  double offset_m = 0.0;
  std::array<Eigen::Vector2d, 2> segment_G{Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
  double bottom_m = 0.0;  ///< walls: lowest extent (2nd percentile)
  nlohmann::json evidence = nlohmann::json::object();  ///< measured figures behind the node
};

/// Walls and ceiling of `mesh_W` (world frame) in the gravity frame of T_W_G (see the file
/// comment): walls "wall_0".. by decreasing area, then "ceiling" when mapped. Parallel-safe
/// (reads its arguments only); linear in the triangle count per wall found.
std::vector<SurfaceNode> fit_structural_surfaces(const TriangleMesh& mesh_W, const Pose& T_W_G,
                                                 const NavigationConfig& config);

/// Signed distance (m) of a gravity-frame (x, y) from a wall's plane: positive on the room side.
inline double wall_side_m(const SurfaceNode& wall, const Eigen::Vector2d& xy_G) {
  return wall.normal_G.dot(xy_G) - wall.offset_m;
}
/// Position of (x, y) along a wall, as a fraction of its segment (0 at segment_G[0], 1 at [1]).
double along_wall(const SurfaceNode& wall, const Eigen::Vector2d& xy_G);

}  // namespace semap
