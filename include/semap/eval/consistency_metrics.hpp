#pragma once
// Ground-truth-free semantic consistency of a labelled mesh (issue 38): does the map say what
// its geometry says? A floor is horizontal and low, a wall vertical, a ceiling horizontal; a
// table top called floor, a wall called floor, a ceiling called wall show up here without
// any ground truth. Figures are area-weighted over the mesh triangles:
//  - A triangle's class is a label at least two of its vertices carry, else its first
//    vertex's (triangle_label in core/gravity.hpp).
//  - labelled_area_share: share of the mesh area whose class is not 0 (unlabelled); per class
//    the share of the whole mesh area.
//  - Agreement, in the gravity frame of estimate_gravity (mesh + trajectory): floor and
//    ceiling agree when the ABSOLUTE angle between the triangle normal and the vertical axis is
//    within agreement_deg (either winding: meshes from other tools may wind either way, and a
//    horizontal surface is what the label claims); walls agree when the normal is within
//    agreement_deg of horizontal. facing_agreement additionally uses the winding as stored,
//    which semap's own meshes point toward free space (the side the cameras saw): floor normal
//    within agreement_deg of up, ceiling within it of down. A floor label on a table's
//    underside or on the ceiling is horizontal but faces the wrong way.
//  - floor_thickness_m: the 5 % .. 95 % spread of the floor-labelled area's heights along up
//    (area-weighted quantiles of the triangle centroids). One floor plane gives a few cm of
//    reconstruction noise; table tops labelled floor make it ~0.7 m.
#include <filesystem>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "semap/core/gravity.hpp"
#include "semap/core/labels.hpp"
#include "semap/core/point_cloud.hpp"
#include "semap/core/pose.hpp"

namespace semap {

struct ConsistencyOptions {
  double agreement_deg = 20.0;         ///< normal tolerance of floor/ceiling (vertical) and wall (horizontal)
  double thickness_low_quantile = 0.05;   ///< floor_thickness_m spans these area quantiles
  double thickness_high_quantile = 0.95;
  int top_classes = 10;                ///< classes listed in `classes`
  GravityOptions gravity;
};

/// One structural class: its area and how much of it the geometry agrees with.
struct ClassAgreement {
  double area_m2 = 0.0;
  double area_share = 0.0;        ///< of the mesh area
  double agreement = 0.0;         ///< share of area_m2 with an agreeing normal (either winding)
  double facing_agreement = 0.0;  ///< floor/ceiling: same, as wound (up / down); wall: = agreement
};

struct ClassArea {
  ClassId class_id = 0;
  double area_m2 = 0.0;
  double area_share = 0.0;  ///< of the mesh area
};

struct SemanticConsistency {
  size_t triangles = 0;  ///< with a positive, finite area (the others are left out)
  double mesh_area_m2 = 0.0;
  double labelled_area_share = 0.0;
  std::vector<ClassArea> classes;  ///< labelled classes, largest area first, at most top_classes
  ClassAgreement floor, wall, ceiling;
  /// Floor-labelled heights along up (world frame, as gravity.floor_height_m); nullopt without
  /// floor-labelled area.
  std::optional<double> floor_thickness_m, floor_height_low_m, floor_height_high_m;
  GravityEstimate gravity;
  double agreement_deg = 0.0;  ///< the tolerance used
};

/// See the file comment. Never throws; an empty mesh gives zeros.
SemanticConsistency evaluate_consistency(const TriangleMesh& mesh, const Trajectory& trajectory,
                                         const ConsistencyOptions& options = {});
/// Reads OUT/mesh.ply and OUT/trajectory.txt (optional: without it the gravity estimate falls
/// back to the floor labels or +z), then evaluate_consistency. Throws semap::Error naming the
/// folder or file: OUT not a folder, mesh.ply missing, unreadable or without triangles,
/// trajectory.txt malformed.
SemanticConsistency evaluate_consistency_folder(const std::filesystem::path& out_dir,
                                                const ConsistencyOptions& options = {});

nlohmann::json to_json(const SemanticConsistency& consistency);
nlohmann::json to_json(const GravityEstimate& gravity);

}  // namespace semap
