#include "semap/navigation/structure.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numbers>
#include <optional>

#include "semap/core/gravity.hpp"
#include "semap/core/labels.hpp"

namespace semap {
namespace {

constexpr double kAzimuthBinDeg = 5.0;
constexpr int kAzimuthBins = 72;  // 360 / 5
constexpr double kCeilingBinM = 0.04;
constexpr double kExtentQuantile = 0.02;  // walls span their inliers' 2nd..98th percentile
constexpr int kMaxWalls = 64;             // bounds the work on pathological meshes
constexpr double kMinWallLabelShare = 0.5;  // a plane mostly labelled wall is a wall at any height

double deg_to_rad(double deg) { return deg * std::numbers::pi / 180.0; }

/// A mesh triangle in the gravity frame.
struct Patch {
  Eigen::Vector3d normal_G, centroid_G;
  double area_m2;
  ClassId label;
};

/// Structural classes (and none) may belong to a wall or the ceiling; object classes never.
bool structural_or_unlabelled(ClassId c) {
  return c == id(Label::kUnlabelled) || c == id(Label::kPicture) || (is_stuff(c) && c != id(Label::kFloor));
}

std::vector<Patch> patches_of(const TriangleMesh& mesh_W, const Pose& T_W_G) {
  const Pose T_G_W = T_W_G.inverse();
  std::vector<Patch> out;
  for (size_t t = 0; t < mesh_W.triangles.size(); ++t) {
    const TriangleGeometry g = triangle_geometry(mesh_W, t);
    const ClassId label = triangle_label(mesh_W, t);
    if (!(g.area_m2 > 0.0) || !structural_or_unlabelled(label)) continue;
    out.push_back({T_G_W.rotation() * g.normal, T_G_W * g.centroid, g.area_m2, label});
  }
  return out;
}

int azimuth_bin(const Eigen::Vector2d& n) {
  const double deg = std::atan2(n.y(), n.x()) * 180.0 / std::numbers::pi;
  return static_cast<int>(std::floor((deg + 360.0) / kAzimuthBinDeg)) % kAzimuthBins;
}

/// The bin whose sum with its two neighbours is largest (wrapping when `circular`); the sum too.
std::pair<int, double> peak_bin(const std::vector<double>& h, bool circular) {
  const int n = static_cast<int>(h.size());
  std::pair<int, double> best{-1, 0.0};
  for (int b = 0; b < n; ++b) {
    double sum = h[b];
    for (int d : {-1, 1}) {
      const int k = b + d;
      if (k >= 0 && k < n) sum += h[k];
      else if (circular) sum += h[(k + n) % n];
    }
    if (sum > best.second) best = {b, sum};
  }
  return best;
}

/// Inliers of the plane (unit horizontal normal n, offset d) among `live` vertical patches.
std::vector<size_t> plane_inliers(const std::vector<Patch>& p, const std::vector<size_t>& live,
                                  const Eigen::Vector2d& n, double d, double min_cos, double tolerance_m) {
  std::vector<size_t> in;
  for (size_t i : live) {
    const Eigen::Vector2d ni = p[i].normal_G.head<2>().normalized();
    if (ni.dot(n) >= min_cos && std::abs(n.dot(p[i].centroid_G.head<2>()) - d) <= tolerance_m) in.push_back(i);
  }
  return in;
}

/// The densest offset along n among patches facing within min_cos of n.
double peak_offset(const std::vector<Patch>& p, const std::vector<size_t>& live, const Eigen::Vector2d& n,
                   double min_cos, double bin_m) {
  std::vector<std::pair<double, double>> offsets;
  double lo = 1e18, hi = -1e18;
  for (size_t i : live)
    if (p[i].normal_G.head<2>().normalized().dot(n) >= min_cos) {
      const double d = n.dot(p[i].centroid_G.head<2>());
      offsets.emplace_back(d, p[i].area_m2);
      lo = std::min(lo, d), hi = std::max(hi, d);
    }
  if (offsets.empty()) return 0.0;
  const size_t bins = std::min<size_t>(100000, static_cast<size_t>((hi - lo) / bin_m) + 1);
  std::vector<double> h(bins, 0.0);
  for (const auto& [d, a] : offsets) h[std::min(bins - 1, static_cast<size_t>((d - lo) / bin_m))] += a;
  return lo + (peak_bin(h, false).first + 0.5) * bin_m;
}

/// The wall node of a refined inlier set.
SurfaceNode wall_node(const std::vector<Patch>& p, const std::vector<size_t>& in, const Eigen::Vector2d& n, double d) {
  SurfaceNode w;
  w.kind = SurfaceKind::kWall;
  w.normal_G = n, w.offset_m = d;
  const Eigen::Vector2d along(-n.y(), n.x());
  std::vector<std::pair<double, double>> s, z;
  double wall_area = 0.0, residual2 = 0.0;
  for (size_t i : in) {
    w.area_m2 += p[i].area_m2;
    wall_area += p[i].label == id(Label::kWall) ? p[i].area_m2 : 0.0;
    const double r = n.dot(p[i].centroid_G.head<2>()) - d;
    residual2 += p[i].area_m2 * r * r;
    s.emplace_back(along.dot(p[i].centroid_G.head<2>()), p[i].area_m2);
    z.emplace_back(p[i].centroid_G.z(), p[i].area_m2);
  }
  const double s0 = weighted_quantile(s, kExtentQuantile), s1 = weighted_quantile(s, 1.0 - kExtentQuantile);
  w.segment_G = {d * n + s0 * along, d * n + s1 * along};
  w.bottom_m = weighted_quantile(z, kExtentQuantile);
  w.height_m = weighted_quantile(z, 1.0 - kExtentQuantile);
  w.evidence = {{"triangles", in.size()},
                {"wall_label_share", wall_area / w.area_m2},
                {"plane_rms_m", std::sqrt(residual2 / w.area_m2)}};
  return w;
}

std::vector<SurfaceNode> fit_walls(const std::vector<Patch>& patches, const NavigationConfig& config) {
  const double max_vertical = std::sin(deg_to_rad(config.vertical_tolerance_deg));
  const double min_cos = std::cos(deg_to_rad(config.vertical_tolerance_deg));
  std::vector<size_t> live;
  for (size_t i = 0; i < patches.size(); ++i)
    if (std::abs(patches[i].normal_G.z()) <= max_vertical) live.push_back(i);
  std::vector<SurfaceNode> walls;
  for (int round = 0; round < 4 * kMaxWalls && walls.size() < kMaxWalls && !live.empty(); ++round) {
    std::vector<double> h(kAzimuthBins, 0.0);
    for (size_t i : live) h[azimuth_bin(patches[i].normal_G.head<2>())] += patches[i].area_m2;
    const auto [bin, peak_area] = peak_bin(h, true);
    if (bin < 0 || peak_area < config.wall_min_area_m2) break;
    const double azimuth = deg_to_rad((bin + 0.5) * kAzimuthBinDeg);
    Eigen::Vector2d n(std::cos(azimuth), std::sin(azimuth));
    double d = peak_offset(patches, live, n, min_cos, config.wall_plane_tolerance_m);
    std::vector<size_t> in = plane_inliers(patches, live, n, d, min_cos, config.wall_plane_tolerance_m);
    if (!in.empty()) {  // refit: area-weighted mean normal and offset
      Eigen::Vector2d sum = Eigen::Vector2d::Zero();
      for (size_t i : in) sum += patches[i].area_m2 * patches[i].normal_G.head<2>().normalized();
      n = sum.normalized();
      double offset = 0.0, area = 0.0;
      for (size_t i : in) offset += patches[i].area_m2 * n.dot(patches[i].centroid_G.head<2>()), area += patches[i].area_m2;
      d = offset / area;
      in = plane_inliers(patches, live, n, d, min_cos, config.wall_plane_tolerance_m);
    }
    if (in.empty()) {  // the peak's patches scatter over offsets: drop the peak bin's patches
      const int peak = bin;  // clang 14 cannot capture a structured binding
      std::erase_if(live, [&](size_t i) { return azimuth_bin(patches[i].normal_G.head<2>()) == peak; });
      continue;
    }
    SurfaceNode w = wall_node(patches, in, n, d);
    const bool labelled_wall = w.evidence["wall_label_share"].get<double>() >= kMinWallLabelShare;
    if (w.area_m2 >= config.wall_min_area_m2 && (labelled_wall || w.height_m >= config.wall_min_top_m))
      walls.push_back(std::move(w));
    std::vector<size_t> rest;
    std::set_difference(live.begin(), live.end(), in.begin(), in.end(), std::back_inserter(rest));
    live.swap(rest);
  }
  std::sort(walls.begin(), walls.end(), [](const SurfaceNode& a, const SurfaceNode& b) { return a.area_m2 > b.area_m2; });
  for (size_t k = 0; k < walls.size(); ++k) walls[k].id = "wall_" + std::to_string(k);
  return walls;
}

std::optional<SurfaceNode> fit_ceiling(const std::vector<Patch>& patches, const NavigationConfig& config) {
  const double min_cos = std::cos(deg_to_rad(config.vertical_tolerance_deg));
  std::vector<std::pair<double, double>> z;  // (height, area)
  double hi = config.ceiling_min_height_m;
  for (const Patch& p : patches)
    if (-p.normal_G.z() >= min_cos && p.centroid_G.z() >= config.ceiling_min_height_m &&
        (p.label == id(Label::kCeiling) || p.label == id(Label::kUnlabelled)))
      z.emplace_back(p.centroid_G.z(), p.area_m2), hi = std::max(hi, p.centroid_G.z());
  if (z.empty()) return std::nullopt;
  const size_t bins = std::min<size_t>(100000, static_cast<size_t>((hi - config.ceiling_min_height_m) / kCeilingBinM) + 2);
  std::vector<double> h(bins, 0.0);
  for (const auto& [height, area] : z)
    h[std::min(bins - 1, static_cast<size_t>((height - config.ceiling_min_height_m) / kCeilingBinM))] += area;
  // The densest bin pair.
  size_t best = 0;
  for (size_t b = 0; b + 1 < bins; ++b)
    if (h[b] + h[b + 1] > h[best] + h[best + 1]) best = b;
  const double lo_m = config.ceiling_min_height_m + best * kCeilingBinM, hi_m = lo_m + 2 * kCeilingBinM;
  std::vector<std::pair<double, double>> band;
  for (const auto& [height, area] : z)
    if (height >= lo_m && height < hi_m) band.emplace_back(height, area);
  SurfaceNode c;
  c.id = "ceiling";
  c.kind = SurfaceKind::kCeiling;
  for (const auto& [height, area] : band) c.area_m2 += area;
  if (c.area_m2 < config.wall_min_area_m2) return std::nullopt;
  c.height_m = weighted_quantile(band, 0.5);
  double candidate_area_m2 = 0.0;
  for (const auto& hz : z) candidate_area_m2 += hz.second;
  c.evidence = {{"triangles", band.size()}, {"candidate_area_m2", candidate_area_m2}};
  return c;
}

}  // namespace

double along_wall(const SurfaceNode& wall, const Eigen::Vector2d& xy_G) {
  const Eigen::Vector2d a = wall.segment_G[0], ab = wall.segment_G[1] - a;
  const double len2 = ab.squaredNorm();
  return len2 > 0.0 ? (xy_G - a).dot(ab) / len2 : 0.0;
}

std::vector<SurfaceNode> fit_structural_surfaces(const TriangleMesh& mesh_W, const Pose& T_W_G,
                                                 const NavigationConfig& config) {
  const std::vector<Patch> patches = patches_of(mesh_W, T_W_G);
  std::vector<SurfaceNode> out = fit_walls(patches, config);
  if (auto ceiling = fit_ceiling(patches, config)) out.push_back(std::move(*ceiling));
  return out;
}

}  // namespace semap
