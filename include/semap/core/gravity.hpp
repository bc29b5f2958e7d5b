#pragma once
// Gravity-aligned frame of a map (issue 38): which way is up, where the floor is, and the
// world-from-gravity transform, estimated from the mesh and the camera trajectory alone, whatever
// the dataset's world convention (TUM and 7-Scenes: the first camera or the motion-capture
// frame; ScanNet: z up). The report's top-down picture uses it; the viewer
// (viewer/src/main.js estimateUp) does the same except for the level-axes prior (step 1).
//
// Up:
//  1. Prior: hand-held and robot cameras are held upright on average: the mean of the
//     cameras' up axes (-y of the optical frame) points against gravity, but leans toward
//     where they looked when they pitch down at tables (25 deg in 7-Scenes redkitchen). Their
//     x axes (image rows) stay level however they pitch, so when the x axes span a plane (the
//     camera turned) up is the direction most perpendicular to all of them, turned to agree
//     with the mean -y. Without a trajectory: the floor-labelled triangles' mean normal turned
//     toward the mesh centre, else +z. The floor labels also overrule the cameras' prior when
//     at least twice as much floor-labelled area faces their own dominant normal as faces the
//     prior (a camera held pitched down that pans about its own y axis sweeps its x axes
//     through a tilted plane: TUM fr1_rpy's level-axes prior is 50 deg off); method
//     floor_labels then.
//  2. Refinement (refine_iterations times): the area-weighted mean normal of the triangles whose
//     normal lies within prior_cone_deg of the current up (each turned to agree with it):
//     floor-labelled ones when they hold at least min_refine_area_m2, else every such triangle
//     (floor, table tops, ceiling). Walls are ~90 deg away and never enter.
//  3. Floor plane: once the floor is found (below), gravity is perpendicular to it: up becomes
//     the normal of the least-squares plane through the near-horizontal triangles within
//     floor_plane_band_m of the floor height, when they span floor_plane_min_extent_m both
//     ways, and the floor height is found again (refine_iterations times). The mean normal of
//     step 2 mixes in table tops and averages noisy triangle normals; in 7-Scenes redkitchen it
//     leaves the floor tilted 3 deg, 0.15 m of height across the room.
// Floor: among near-horizontal triangles (normal within floor_normal_deg of the vertical axis,
// either winding) lying below the cameras' mean height (the mesh centre without a trajectory; so
// the ceiling never counts), the lowest height bin (pair of floor_bin_m bins, so a floor on a
// bin edge is not split) holding min_floor_share of their area is the floor; its height is the
// area-weighted median there. The floor is the lowest LARGE horizontal surface: a table top
// above a visible floor is never taken; a scene that shows table tops but no floor at all
// reports the lowest table as floor (nothing in the geometry tells them apart).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "semap/core/labels.hpp"
#include "semap/core/params.hpp"
#include "semap/core/point_cloud.hpp"
#include "semap/core/pose.hpp"

namespace semap {

struct GravityOptions {
  /// The cameras' x axes give the prior when the second eigenvalue of their scatter (mean of
  /// x x^T) reaches this (~13 deg of turning) and the smallest is at most half of it.
  double min_x_axis_spread = 0.05;
  double prior_cone_deg = 25.0;      ///< triangles within this of the current up refine it
  int refine_iterations = 3;         ///< refinements (each re-selects the triangles)
  double min_refine_area_m2 = 0.05;  ///< less area in the cone: no refinement from that set
  double floor_normal_deg = 20.0;    ///< floor candidates: normal within this of vertical
  double floor_bin_m = 0.04;         ///< height histogram bin
  double min_floor_share = 0.10;     ///< the floor bin pair holds at least this share of candidate area
  double min_floor_area_m2 = 0.10;   ///< less candidate area than this: no floor
  double floor_plane_band_m = 0.06;  ///< floor plane: near-horizontal triangles within this of the floor height
  double floor_plane_min_extent_m = 0.5;  ///< ... spanning at least this both ways give up
};

/// How up_W was found.
enum class GravityMethod : uint8_t {
  kZAxis,                  ///< no trajectory, no floor labels: +z of the world
  kFloorLabels,            ///< floor-labelled triangles (no trajectory, or it contradicts them)
  kTrajectory,             ///< the cameras' mean up; no horizontal surface to refine it
  kTrajectoryFloorLabels,  ///< trajectory prior refined by floor-labelled triangles
  kTrajectoryHorizontal,   ///< trajectory prior refined by every near-horizontal triangle
};
inline constexpr EnumNames<GravityMethod, 5> kGravityMethodNames{{
    {GravityMethod::kZAxis, "z_axis"},
    {GravityMethod::kFloorLabels, "floor_labels"},
    {GravityMethod::kTrajectory, "trajectory"},
    {GravityMethod::kTrajectoryFloorLabels, "trajectory+floor_labels"},
    {GravityMethod::kTrajectoryHorizontal, "trajectory+horizontal_surfaces"},
}};

struct GravityEstimate {
  Eigen::Vector3d up_W = Eigen::Vector3d::UnitZ();  ///< unit, world frame, against gravity
  GravityMethod method = GravityMethod::kZAxis;
  bool floor_found = false;
  double floor_height_m = 0.0;  ///< up_W . p on the floor plane (meaningful when floor_found)
  /// World from gravity frame: z = up_W, x = world x (else y) made horizontal; origin on the
  /// floor plane under the mesh's bounding-box centre (the trajectory's mean without a mesh);
  /// without a floor, at the height of the lowest mesh vertex (else the lowest camera).
  Pose T_W_G = Pose::Identity();
  double prior_to_up_deg = 0.0;  ///< angle the refinement turned the prior by
  bool up_from_floor_plane = false;  ///< up is the floor plane's normal (step 3)
};

/// See the file comment. Never throws; an empty mesh and trajectory give +z.
GravityEstimate estimate_gravity(const TriangleMesh& mesh, const Trajectory& trajectory,
                                 const GravityOptions& options = {});

// Triangle helpers shared by the gravity estimate and the semantic consistency metrics.

/// Area (m^2) and unit normal of triangle t as wound (cross(v1 - v0, v2 - v0)); area 0 and a
/// zero normal for degenerate or non-finite triangles.
struct TriangleGeometry {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double area_m2 = 0.0;
};
TriangleGeometry triangle_geometry(const TriangleMesh& mesh, size_t t);

/// A triangle's class: a label at least two of its vertices carry, else its first vertex's;
/// 0 (unlabelled) when the mesh has no labels.
ClassId triangle_label(const TriangleMesh& mesh, size_t t);

/// Weighted quantile (q in [0, 1]) of (value, weight) pairs: the smallest value whose
/// cumulative weight reaches q of the total; 0 for an empty set.
double weighted_quantile(std::vector<std::pair<double, double>> value_weight, double q);

}  // namespace semap
