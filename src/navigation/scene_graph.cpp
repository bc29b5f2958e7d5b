#include "semap/navigation/scene_graph.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>

#include "semap/core/gravity.hpp"

namespace semap {
namespace {

// z extent of an object's box. Top: the 98th percentile (a stray point above does not lift the
// surface things rest on). Bottom: the k-th lowest point, k = max(5, n / 500): a percentile
// would climb up the thin legs of a table or chair, which hold few of its points.
constexpr double kBoxHighQuantile = 0.98;
constexpr size_t kBottomMinPoints = 5, kBottomPointsPer = 500;

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

SceneObjectNode object_node(const ObjectSummary& o, const Pose& T_G_W, const OccupancyGrid& grid) {
  SceneObjectNode n;
  n.id = o.id;
  n.class_name = std::string(class_name(o.class_id));
  n.confidence = o.confidence;
  n.point_count = o.points.size();
  n.centroid_G = T_G_W * o.centroid.cast<double>();
  std::vector<Eigen::Vector3d> points_G;
  points_G.reserve(o.points.size());
  std::set<std::pair<int, int>> cells;
  const double r = grid.resolution_m;
  for (const Eigen::Vector3f& p : o.points) {
    points_G.push_back(T_G_W * p.cast<double>());
    const Eigen::Vector2d xy = points_G.back().head<2>();
    cells.emplace(static_cast<int>(std::floor(xy.x() / r)), static_cast<int>(std::floor(xy.y() / r)));
  }
  for (const auto& [x, y] : cells) n.footprint_G.emplace_back((x + 0.5) * r, (y + 0.5) * r);
  n.box = gravity_box(points_G);
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
    if (floor_mapped && std::abs(bottom) <= tol) best = "floor", best_top = 0.0, best_overlap = 1.0;
    for (const SceneObjectNode& b : g.objects) {
      if (b.id == a.id) continue;
      const double top = b.box.top_m();
      if (std::abs(bottom - top) > tol || top >= a.centroid_G.z() || top <= best_top) continue;
      const double overlap = footprint_overlap(a, b.box, tol);
      if (overlap < 0.5) continue;
      best = object_node_id(b.id), best_top = top, best_overlap = overlap;
    }
    if (best.empty()) continue;
    g.edges.push_back({Relation::kOn, object_node_id(a.id), best,
                       {{"bottom_m", bottom}, {"support_top_m", best_top}, {"gap_m", bottom - best_top},
                        {"footprint_overlap", best_overlap}, {"tolerance_m", tol}}});
  }
}

void add_in_and_near_edges(SceneGraph& g) {
  for (const SceneObjectNode& a : g.objects)
    for (const SceneObjectNode& b : g.objects) {
      if (a.id == b.id) continue;
      const double va = a.box.size_m.prod(), vb = b.box.size_m.prod();
      if (b.box.contains(a.centroid_G) && va < 0.5 * vb)
        g.edges.push_back({Relation::kIn, object_node_id(a.id), object_node_id(b.id),
                           {{"volume_ratio", vb > 0 ? va / vb : 0.0}, {"centroid_inside", true}}});
      const double d = (a.centroid_G - b.centroid_G).norm();
      if (a.id < b.id && d <= g.config.near_distance_m)
        g.edges.push_back({Relation::kNear, object_node_id(a.id), object_node_id(b.id),
                           {{"distance_m", d}, {"threshold_m", g.config.near_distance_m}}});
    }
}

/// Places: connected free regions (8-neighbourhood) of at least min_place_area_m2; and each
/// object's in_place edge to the place of the free cell nearest its footprint centre.
void add_places(SceneGraph& g, const OccupancyGrid& grid) {
  if (grid.width == 0) return;
  cv::Mat free(grid.height, grid.width, CV_8UC1);
  for (int iy = 0; iy < grid.height; ++iy)
    for (int ix = 0; ix < grid.width; ++ix) free.at<uint8_t>(iy, ix) = grid.state[grid.index(ix, iy)] == CellState::kFree;
  cv::Mat components, stats, centroids;
  const int n = cv::connectedComponentsWithStats(free, components, stats, centroids, 8, CV_32S);
  const double cell_area = grid.resolution_m * grid.resolution_m;
  std::map<int, size_t> place_of_component;
  for (int k = 1; k < n; ++k) {
    const int cells = stats.at<int>(k, cv::CC_STAT_AREA);
    if (cells * cell_area < g.config.min_place_area_m2) continue;
    PlaceNode p;
    p.id = "place_" + std::to_string(g.places.size());
    p.cells = cells;
    p.area_m2 = cells * cell_area;
    p.centroid_G = grid.origin_G + Eigen::Vector2d(centroids.at<double>(k, 0) + 0.5, centroids.at<double>(k, 1) + 0.5) *
                                       grid.resolution_m;
    place_of_component[k] = g.places.size();
    g.places.push_back(p);
  }
  if (g.places.empty()) return;
  for (const SceneObjectNode& o : g.objects) {
    double best_d2 = 1e18;
    int best_k = 0;
    for (int iy = 0; iy < grid.height; ++iy)
      for (int ix = 0; ix < grid.width; ++ix) {
        const int k = components.at<int>(iy, ix);
        if (!place_of_component.count(k)) continue;
        const double d2 = (grid.cell_centre(ix, iy) - o.box.center_G.head<2>()).squaredNorm();
        if (d2 < best_d2) best_d2 = d2, best_k = k;
      }
    if (best_k == 0) continue;
    g.edges.push_back({Relation::kInPlace, object_node_id(o.id), g.places[place_of_component[best_k]].id,
                       {{"nearest_free_cell_m", std::sqrt(best_d2)}}});
  }
}

}  // namespace

std::string object_node_id(uint32_t id) { return "object_" + std::to_string(id); }

bool GravityBox::footprint_contains(const Eigen::Vector2d& xy_G, double margin_m) const {
  const Eigen::Vector2d d = xy_G - center_G.head<2>();
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const Eigen::Vector2d local(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  return std::abs(local.x()) <= 0.5 * size_m.x() + margin_m && std::abs(local.y()) <= 0.5 * size_m.y() + margin_m;
}

bool GravityBox::contains(const Eigen::Vector3d& p_G) const {
  return footprint_contains(p_G.head<2>()) && p_G.z() >= bottom_m() && p_G.z() <= top_m();
}

GravityBox gravity_box(const std::vector<Eigen::Vector3d>& points_G) {
  GravityBox box;
  if (points_G.empty()) return box;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points_G) mean += p.head<2>();
  mean /= static_cast<double>(points_G.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const auto& p : points_G) scatter += (p.head<2>() - mean) * (p.head<2>() - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  const Eigen::Vector2d major = eig.eigenvectors().col(1);
  box.yaw_rad = std::atan2(major.y(), major.x());
  const double c = std::cos(box.yaw_rad), s = std::sin(box.yaw_rad);
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e18), hi = -lo;
  std::vector<double> z;
  z.reserve(points_G.size());
  for (const auto& p : points_G) {
    const Eigen::Vector2d local(c * p.x() + s * p.y(), -s * p.x() + c * p.y());
    lo = lo.cwiseMin(local), hi = hi.cwiseMax(local);
    z.push_back(p.z());
  }
  const size_t k = std::min(z.size() - 1, std::max(kBottomMinPoints, z.size() / kBottomPointsPer) - 1);
  std::nth_element(z.begin(), z.begin() + k, z.end());
  const double z_lo = z[k], z_hi = quantile(z, kBoxHighQuantile);
  const Eigen::Vector2d centre_local = 0.5 * (lo + hi);
  box.center_G = {c * centre_local.x() - s * centre_local.y(), s * centre_local.x() + c * centre_local.y(),
                  0.5 * (z_lo + z_hi)};
  box.size_m = {hi.x() - lo.x(), hi.y() - lo.y(), z_hi - z_lo};
  return box;
}

SceneGraph build_scene_graph(const std::vector<ObjectSummary>& objects, const OccupancyGrid& grid,
                             const NavigationConfig& config) {
  SceneGraph g;
  g.config = config;
  g.T_W_G = grid.T_W_G;
  const Pose T_G_W = grid.T_W_G.inverse();
  for (const ObjectSummary& o : objects)
    if (!o.points.empty()) g.objects.push_back(object_node(o, T_G_W, grid));
  const bool floor_mapped = grid.count(CellState::kFree) > 0;
  if (floor_mapped) {
    const double cell_area = grid.resolution_m * grid.resolution_m;
    g.surfaces.push_back({"floor", SurfaceKind::kFloor, 0.0,
                          grid.count(CellState::kFree) * cell_area});
  }
  add_on_edges(g, floor_mapped);
  add_in_and_near_edges(g);
  add_places(g, grid);
  return g;
}

}  // namespace semap
