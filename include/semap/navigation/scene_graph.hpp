#pragma once
// Scene graph of a map (issue 39): objects, structural surfaces and places with their
// relations, what planners and language models read. Written as scene_graph.json; schema in
// README.md ("scene_graph.json"). Frame: the gravity frame G (core/gravity.hpp: z up, z = 0 on
// the floor plane) unless a key says _W (world); metres, radians.
//
// Relations, each with its evidence:
//   on(A, B)       A's bottom (box bottom) lies within on_tolerance_m of B's support height
//                  (support_height: the surface things rest on), B's support lies below the
//                  centre of A's box and B's bottom below A's, and at least half of A's footprint cells overlap B's box footprint
//                  grown by the tolerance. Of several candidates, the highest support wins: one
//                  support per object. An object no other supports rests on the floor when the
//                  floor was mapped and its bottom lies at most floor_support_max_gap_m above it
//                  (a table's legs hidden by chairs); else (wall-mounted, on an unmapped counter)
//                  it has no `on`.
//   in(A, B)       A's box centre lies inside B's box, A's box volume is under half of B's,
//                  A's top is at most on_tolerance_m above B's (a chair pushed under a table
//                  sticks out) and A is not `on` B (a cup on a table is not in it).
//   near(A, B)     centroids at most near_distance_m apart (A < B by id, listed once).
//   in_place(A, P) the room-space cell (navigation/places.hpp) nearest A's box centre belongs
//                  to place P.
//   connected(P, Q) places P and Q (P listed first) share a passage (navigation/places.hpp:
//                  their cells touch where the split cut a door); evidence: passage_width_m,
//                  passage_centre_G (x, y, 0 on the floor), border_cells.
// Nodes besides the objects: the floor (when the grid has free cells), the walls and ceiling
// (navigation/structure.hpp) and the places (navigation/places.hpp). No relation ever has a
// wall or the ceiling as its target: nothing is `on` a wall.
#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "semap/core/pose.hpp"
#include "semap/navigation/navigation_config.hpp"
#include "semap/navigation/occupancy_grid.hpp"
#include "semap/navigation/places.hpp"
#include "semap/navigation/structure.hpp"
#include "semap/objects/object_summary.hpp"

namespace semap {

/// Box with a vertical axis: centre, full sizes along its own x, y and z, yaw about z (rad).
struct GravityBox {
  Eigen::Vector3d center_G = Eigen::Vector3d::Zero();
  Eigen::Vector3d size_m = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;
  /// Whether the (x, y) of a gravity-frame point lies inside the footprint grown by `margin_m`.
  bool footprint_contains(const Eigen::Vector2d& xy_G, double margin_m = 0.0) const;
  bool contains(const Eigen::Vector3d& p_G) const;
  double bottom_m() const { return center_G.z() - 0.5 * size_m.z(); }
  double top_m() const { return center_G.z() + 0.5 * size_m.z(); }
};
/// Vertical box around gravity-frame points: yaw from the footprint's principal axes, x-y extent
/// of every point, z from the k-th lowest point (k = max(5, n / 500)) to the 98th percentile.
GravityBox gravity_box(const std::vector<Eigen::Vector3d>& points_G);
/// The largest connected part of an object's points: points joined through occupied cubes of
/// kMainPartVoxelM (26-neighbourhood), the part holding most points. Stray fragments the object
/// map attached (a chair's leg in a cup) then stretch neither box nor footprint.
inline constexpr double kMainPartVoxelM = 0.04;
std::vector<Eigen::Vector3d> main_part(const std::vector<Eigen::Vector3d>& points_G);
/// Height of the surface things rest on: the densest horizontal layer (pair of kSupportBinM
/// bins holding most points, their median height) among the points at or above the box's
/// mid-height: a table's top, not the 98th percentile of the cups on it.
inline constexpr double kSupportBinM = 0.02;
double support_height(const std::vector<Eigen::Vector3d>& points_G, const GravityBox& box);

struct SceneObjectNode {
  uint32_t id = 0;  ///< the object's id in objects.json
  std::string class_name;
  double confidence = 0.0;
  Eigen::Vector3d centroid_G = Eigen::Vector3d::Zero();
  GravityBox box;                ///< of its main part (main_part)
  double support_height_m = 0.0;  ///< support_height of its main part
  size_t point_count = 0;
  std::vector<Eigen::Vector2d> footprint_G;  ///< centres of the grid cells its main part covers (not serialised)
};

enum class Relation : uint8_t { kOn, kIn, kNear, kInPlace, kConnected };
inline constexpr EnumNames<Relation, 5> kRelationNames{{{Relation::kOn, "on"},
                                                        {Relation::kIn, "in"},
                                                        {Relation::kNear, "near"},
                                                        {Relation::kInPlace, "in_place"},
                                                        {Relation::kConnected, "connected"}}};

struct SceneEdge {
  Relation relation = Relation::kOn;
  std::string source, target;  ///< node ids: "object_<id>", "floor", "place_<k>"
  nlohmann::json evidence;      ///< measured figures behind the relation (metres, fractions)
};

struct SceneGraph {
  Pose T_W_G = Pose::Identity();
  std::vector<SceneObjectNode> objects;
  std::vector<SurfaceNode> surfaces;
  std::vector<PlaceNode> places;
  std::vector<SceneEdge> edges;
  NavigationConfig config;  ///< the thresholds the relations used
};

std::string object_node_id(uint32_t id);

/// Builds nodes and edges (see the file comment). `grid` gives the floor's area, the places and
/// the footprints; an empty grid gives none of them (objects and their mutual relations stay).
/// `structure`: the walls and ceiling (fit_structural_surfaces), listed after the floor.
SceneGraph build_scene_graph(const std::vector<ObjectSummary>& objects, const OccupancyGrid& grid,
                             const std::vector<SurfaceNode>& structure, const NavigationConfig& config);

nlohmann::json to_json(const SceneGraph& graph);
/// Reads a scene_graph.json document; throws semap::Error(source, what is wrong).
SceneGraph scene_graph_from_json(const nlohmann::json& j, const std::string& source);
/// Reads OUT/scene_graph.json (or the file itself).
SceneGraph load_scene_graph(const std::filesystem::path& folder_or_file);

}  // namespace semap

namespace semap {

/// A question to a scene graph (`semap query`): objects of `class_name` (any when empty) that
/// are on / in an object of class `on` / `in` (or "floor", or a node id), and near an object of
/// class `near` (centroid distance at most within_m; the graph's near_distance_m when unset).
struct SceneQuery {
  std::string class_name, on, in, near;
  double within_m = -1.0;
};
/// At most this many matches are listed per object (the nearest first for `near`);
/// "matches_total" counts them all. Bounds the answer on graphs of thousands of objects.
inline constexpr size_t kMaxQueryMatchesPerObject = 16;
/// One JSON object per matching object node: the node (as in scene_graph.json) plus "matches",
/// the relations that satisfied the query with their evidence, and "matches_total". In node
/// order, each given to `emit` as it is found (semap query prints them as JSON lines).
void query_scene_graph(const SceneGraph& graph, const SceneQuery& query,
                       const std::function<void(const nlohmann::json&)>& emit);
/// The same, collected.
std::vector<nlohmann::json> query_scene_graph(const SceneGraph& graph, const SceneQuery& query);

}  // namespace semap
