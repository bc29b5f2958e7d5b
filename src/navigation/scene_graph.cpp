#include "semap/navigation/scene_graph.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

namespace semap {
namespace {

SceneObjectNode object_node(const ObjectSummary& o, const Pose& T_G_W, const OccupancyGrid& grid) {
  SceneObjectNode n;
  n.id = o.id;
  n.class_name = std::string(class_name(o.class_id));
  n.confidence = o.confidence;
  n.point_count = o.points.size();
  n.centroid_G = T_G_W * o.centroid.cast<double>();
  std::vector<Eigen::Vector3d> points_G;
  points_G.reserve(o.points.size());
  for (const Eigen::Vector3f& p : o.points) points_G.push_back(T_G_W * p.cast<double>());
  points_G = main_part(points_G);
  std::set<std::pair<int, int>> cells;
  const double r = grid.resolution_m;
  for (const Eigen::Vector3d& p : points_G)
    cells.emplace(static_cast<int>(std::floor(p.x() / r)), static_cast<int>(std::floor(p.y() / r)));
  for (const auto& [x, y] : cells) n.footprint_G.emplace_back((x + 0.5) * r, (y + 0.5) * r);
  n.box = gravity_box(points_G);
  n.support_height_m = support_height(points_G, n.box);
  return n;
}

/// Share of a's footprint cells inside b's footprint grown by `margin_m`.
double footprint_overlap(const SceneObjectNode& a, const GravityBox& b, double margin_m) {
  if (a.footprint_G.empty()) return 0.0;
  size_t inside = 0;
  for (const Eigen::Vector2d& c : a.footprint_G) inside += b.footprint_contains(c, margin_m);
  return static_cast<double>(inside) / a.footprint_G.size();
}

void add_on_edges(SceneGraph& g, bool floor_mapped) {
  const double tol = g.config.on_tolerance_m;
  for (const SceneObjectNode& a : g.objects) {
    const double bottom = a.box.bottom_m();
    std::string best;
    double best_top = -1e9, best_overlap = 0.0;
    for (const SceneObjectNode& b : g.objects) {
      if (b.id == a.id) continue;
      const double top = b.support_height_m;
      if (std::abs(bottom - top) > tol || top >= a.box.center_G.z() || top <= best_top) continue;
      if (b.box.bottom_m() >= bottom) continue;  // a support stands lower than what it carries
      const double overlap = footprint_overlap(a, b.box, tol);
      if (overlap < 0.5) continue;
      best = object_node_id(b.id), best_top = top, best_overlap = overlap;
    }
    if (best.empty() && floor_mapped && bottom >= -tol && bottom <= g.config.floor_support_max_gap_m)
      best = "floor", best_top = 0.0, best_overlap = 1.0;
    if (best.empty()) continue;
    g.edges.push_back({Relation::kOn, object_node_id(a.id), best,
                       {{"bottom_m", bottom}, {"support_top_m", best_top}, {"gap_m", bottom - best_top},
                        {"footprint_overlap", best_overlap}, {"tolerance_m", tol}}});
  }
}

/// Whether the graph already has on(a, b).
bool rests_on(const SceneGraph& g, const SceneObjectNode& a, const SceneObjectNode& b) {
  return std::any_of(g.edges.begin(), g.edges.end(), [&](const SceneEdge& e) {
    return e.relation == Relation::kOn && e.source == object_node_id(a.id) && e.target == object_node_id(b.id);
  });
}

void add_in_and_near_edges(SceneGraph& g) {
  const double tol = g.config.on_tolerance_m;
  std::vector<SceneEdge> edges;
  for (const SceneObjectNode& a : g.objects)
    for (const SceneObjectNode& b : g.objects) {
      if (a.id == b.id) continue;
      const double va = a.box.size_m.prod(), vb = b.box.size_m.prod();
      if (b.box.contains(a.box.center_G) && va < 0.5 * vb && a.box.top_m() <= b.box.top_m() + tol && !rests_on(g, a, b))
        edges.push_back({Relation::kIn, object_node_id(a.id), object_node_id(b.id),
                         {{"volume_ratio", vb > 0 ? va / vb : 0.0},
                          {"centre_inside", true},
                          {"top_below_m", b.box.top_m() - a.box.top_m()}}});
      const double d = (a.centroid_G - b.centroid_G).norm();
      if (a.id < b.id && d <= g.config.near_distance_m)
        edges.push_back({Relation::kNear, object_node_id(a.id), object_node_id(b.id),
                         {{"distance_m", d}, {"threshold_m", g.config.near_distance_m}}});
    }
  g.edges.insert(g.edges.end(), edges.begin(), edges.end());
}

/// Places (navigation/places.hpp), a connected edge per passage between two, and each object's
/// in_place edge: the place of the room-space cell nearest its box centre.
void add_places(SceneGraph& g, const OccupancyGrid& grid) {
  PlaceMap places = segment_places(grid, g.config);
  g.places = std::move(places.places);
  if (g.places.empty()) return;
  for (const PlacePassage& p : places.passages)
    g.edges.push_back({Relation::kConnected, g.places[p.a].id, g.places[p.b].id,
                       {{"passage_width_m", p.width_m},
                        {"passage_centre_G", {p.centre_G.x(), p.centre_G.y(), 0.0}},
                        {"border_cells", p.border_cells}}});
  for (const SceneObjectNode& o : g.objects) {
    double best_d2 = std::numeric_limits<double>::infinity();
    int best = -1;
    for (int iy = 0; iy < grid.height; ++iy)
      for (int ix = 0; ix < grid.width; ++ix) {
        const int p = places.place_of_cell[grid.index(ix, iy)];
        if (p < 0) continue;
        const double d2 = (grid.cell_centre(ix, iy) - o.box.center_G.head<2>()).squaredNorm();
        if (d2 < best_d2) best_d2 = d2, best = p;
      }
    if (best < 0) continue;
    g.edges.push_back({Relation::kInPlace, object_node_id(o.id), g.places[best].id,
                       {{"nearest_place_cell_m", std::sqrt(best_d2)}}});
  }
}

}  // namespace

std::string object_node_id(uint32_t id) { return "object_" + std::to_string(id); }

SceneGraph build_scene_graph(const std::vector<ObjectSummary>& objects, const OccupancyGrid& grid,
                             const std::vector<SurfaceNode>& structure, const NavigationConfig& config) {
  SceneGraph g;
  g.config = config;
  g.T_W_G = grid.T_W_G;
  const Pose T_G_W = grid.T_W_G.inverse();
  for (const ObjectSummary& o : objects)
    if (!o.points.empty()) g.objects.push_back(object_node(o, T_G_W, grid));
  const bool floor_mapped = grid.count(CellState::kFree) > 0;
  if (floor_mapped) {
    const double cell_area = grid.resolution_m * grid.resolution_m;
    SurfaceNode floor{"floor", SurfaceKind::kFloor, 0.0, grid.count(CellState::kFree) * cell_area};
    floor.evidence = {{"free_cells", grid.count(CellState::kFree)}, {"plane", "z = 0 of the gravity frame"}};
    g.surfaces.push_back(std::move(floor));
  }
  g.surfaces.insert(g.surfaces.end(), structure.begin(), structure.end());
  add_on_edges(g, floor_mapped);
  add_in_and_near_edges(g);
  add_places(g, grid);
  return g;
}

}  // namespace semap
