#include "semap/pipeline/navigation_outputs.hpp"

#include "core/archive.hpp"
#include "core/paths.hpp"
#include "semap/eval/consistency_metrics.hpp"
#include "semap/mapper.hpp"
#include "semap/navigation/map_files.hpp"

namespace semap {

NavigationMaps build_navigation_maps(const Mapper& mapper, const TriangleMesh& mesh, const Trajectory& trajectory,
                                     const std::vector<ObjectSummary>& objects) {
  NavigationMaps maps;
  maps.gravity = estimate_gravity(mesh, trajectory);
  const NavigationConfig& config = mapper.config().navigation;
  mapper.read_tsdf([&](const TsdfMap& map) { maps.grid = build_occupancy_grid(map, maps.gravity.T_W_G, config); });
  const std::vector<SurfaceNode> structure = fit_structural_surfaces(mesh, maps.gravity.T_W_G, config);
  maps.scene_graph = build_scene_graph(objects, maps.grid, structure, config);
  return maps;
}

NavigationMaps build_navigation_maps(const Mapper& mapper) {
  return build_navigation_maps(mapper, mapper.mesh(), mapper.trajectory(), mapper.objects());
}

void write_navigation_maps(const NavigationMaps& maps, const std::filesystem::path& dir) {
  write_navigation_maps(maps.grid, dir);
  write_file_atomic(dir / "scene_graph.json", to_json(maps.scene_graph).dump(2) + "\n");
}

nlohmann::json gravity_report_json(const GravityEstimate& gravity) {
  nlohmann::json j = to_json(gravity);
  nlohmann::json T = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < 4; ++c) row.push_back(gravity.T_W_G.matrix()(r, c));
    T.push_back(row);
  }
  j["T_W_G"] = T;
  return j;
}

nlohmann::json navigation_report_json(const NavigationMaps& maps) {
  const OccupancyGrid& g = maps.grid;
  const double cell_m2 = g.resolution_m * g.resolution_m;
  size_t on = 0;
  for (const SceneEdge& e : maps.scene_graph.edges) on += e.relation == Relation::kOn;
  return {{"grid_cells", {g.width, g.height}},
          {"resolution_m", g.resolution_m},
          {"free_m2", g.count(CellState::kFree) * cell_m2},
          {"occupied_m2", g.count(CellState::kOccupied) * cell_m2},
          {"unknown_m2", g.count(CellState::kUnknown) * cell_m2},
          {"scene_graph", {{"objects", maps.scene_graph.objects.size()},
                           {"places", maps.scene_graph.places.size()},
                           {"edges", maps.scene_graph.edges.size()},
                           {"on_edges", on}}}};
}

std::string encode_gravity_section(const GravityEstimate& gravity) {
  ByteWriter w;
  w.put(static_cast<uint32_t>(1));  // section version
  w.put_bytes(gravity.T_W_G.matrix().data(), 16 * sizeof(double));
  w.put(static_cast<uint8_t>(gravity.floor_found));
  w.put(gravity.floor_height_m);
  w.put_bytes(gravity.up_W.data(), 3 * sizeof(double));
  return std::move(w.bytes());
}

std::optional<Pose> read_map_gravity(const std::filesystem::path& map_file) {
  const ArchiveSections sections = read_map_archive(map_file);
  const auto it = sections.find(kGravitySection);
  if (it == sections.end()) return std::nullopt;
  ByteReader r(it->second, map_file, kGravitySection);
  if (r.get<uint32_t>() != 1) r.fail("unknown gravity section version");
  Pose T_W_G;
  r.read(T_W_G.matrix().data(), 16 * sizeof(double));
  if (!is_valid_pose(T_W_G)) r.fail("T_W_G is not a rigid transform");
  return T_W_G;
}

}  // namespace semap
