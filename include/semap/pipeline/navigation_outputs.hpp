#pragma once
// The robot-facing maps of a Mapper (issue 39): the gravity frame, the occupancy grid with its
// distance field, and the scene graph. write_map_outputs writes them with the other outputs:
//
//   map.pgm, map.yaml, map_labels.png, esdf.npy, esdf.yaml   (navigation/map_files.hpp)
//   scene_graph.json                                          (navigation/scene_graph.hpp)
//   map.semap section "gravity": T_W_G (16 doubles, column-major), floor height, up
#include <filesystem>
#include <optional>
#include <string>

#include "semap/core/gravity.hpp"
#include "semap/navigation/occupancy_grid.hpp"
#include "semap/navigation/scene_graph.hpp"

namespace semap {

class Mapper;

struct NavigationMaps {
  GravityEstimate gravity;
  OccupancyGrid grid;
  SceneGraph scene_graph;
};

/// Gravity from the mesh and trajectory, then the grid from the Mapper's TSDF (read under its
/// lock), the walls and ceiling of the mesh (fit_structural_surfaces) and the scene graph of
/// `objects`, with the Mapper's navigation config.
NavigationMaps build_navigation_maps(const Mapper& mapper, const TriangleMesh& mesh, const Trajectory& trajectory,
                                     const std::vector<ObjectSummary>& objects);
/// The same, reading mesh, trajectory and objects from the Mapper (Mapper-level accessor).
NavigationMaps build_navigation_maps(const Mapper& mapper);

/// map files + scene_graph.json into `dir` (atomic writes).
void write_navigation_maps(const NavigationMaps& maps, const std::filesystem::path& dir);

/// report.json's "gravity" object: up, method, floor, T_W_G (4x4 rows).
nlohmann::json gravity_report_json(const GravityEstimate& gravity);
/// report.json's "navigation" object: grid size and cell counts, scene graph counts.
nlohmann::json navigation_report_json(const NavigationMaps& maps);

/// map.semap's "gravity" section (issue 39); absent from maps written before it.
inline constexpr const char* kGravitySection = "gravity";
std::string encode_gravity_section(const GravityEstimate& gravity);
/// T_W_G of a map.semap's gravity section; nullopt for maps saved before issue 39.
std::optional<Pose> read_map_gravity(const std::filesystem::path& map_file);

}  // namespace semap
