#include "semap/core/gravity.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

namespace semap {
namespace {

double cos_deg(double deg) { return std::cos(deg * std::numbers::pi / 180.0); }

/// A triangle with area, as the estimate sees it.
struct Surface {
  TriangleGeometry geometry;
  bool floor = false;  ///< labelled floor
};

std::vector<Surface> surfaces_of(const TriangleMesh& mesh) {
  std::vector<Surface> out;
  out.reserve(mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const TriangleGeometry g = triangle_geometry(mesh, t);
    if (g.area_m2 > 0.0) out.push_back({g, triangle_label(mesh, t) == id(Label::kFloor)});
  }
  return out;
}

/// Area-weighted sum of the normals within acos(min_cos) of the vertical axis `up` (either
/// winding), each turned to agree with `up`; `area` gets their total area.
Eigen::Vector3d agreeing_normal_sum(const std::vector<Surface>& surfaces, const Eigen::Vector3d& up, double min_cos,
                                    bool floor_only, double& area) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  area = 0.0;
  for (const Surface& s : surfaces) {
    if (floor_only && !s.floor) continue;
    const double c = s.geometry.normal.dot(up);
    if (std::abs(c) < min_cos) continue;
    sum += (c < 0 ? -s.geometry.area_m2 : s.geometry.area_m2) * s.geometry.normal;
    area += s.geometry.area_m2;
  }
  return sum;
}

/// Up from the cameras. A hand-held camera's x axis (image rows) stays nearly level while it
/// pitches to look at tables and floors, so up is the direction most perpendicular to all x
/// axes (smallest eigenvector of their scatter), turned to agree with the mean -y axis. The
/// mean -y alone leans toward where the cameras looked (25 deg in 7-Scenes redkitchen, at the
/// edge of the refinement cone); it stays the prior when the x axes do not span a plane (the
/// camera never turned). nullopt when the -y axes cancel out.
std::optional<Eigen::Vector3d> trajectory_up(const Trajectory& trajectory, double min_x_axis_spread) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : trajectory) {
    sum -= p.T_world_camera.linear().col(1);
    const Eigen::Vector3d x = p.T_world_camera.linear().col(0);
    scatter += x * x.transpose();
  }
  if (trajectory.empty() || !sum.allFinite() || !scatter.allFinite() ||
      sum.norm() < 1e-6 * static_cast<double>(trajectory.size()))
    return std::nullopt;
  const Eigen::Vector3d mean_up = sum.normalized();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter / static_cast<double>(trajectory.size()));
  const Eigen::Vector3d values = eigen.eigenvalues();  // ascending
  if (values(1) < min_x_axis_spread || values(0) > 0.5 * values(1)) return mean_up;
  const Eigen::Vector3d level_up = eigen.eigenvectors().col(0);
  return level_up.dot(mean_up) < 0 ? Eigen::Vector3d(-level_up) : level_up;
}

/// Centre of the bounding box of the finite mesh vertices; nullopt without any.
std::optional<Eigen::Vector3d> mesh_centre(const TriangleMesh& mesh) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const auto& v : mesh.vertices.points) {
    const Eigen::Vector3d p = v.cast<double>();
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if (lo.x() > hi.x()) return std::nullopt;
  return 0.5 * (lo + hi);
}

/// No trajectory: the floor-labelled triangles' mean normal, each turned toward the mesh centre
/// (the room lies above its floor).
std::optional<Eigen::Vector3d> floor_label_up(const std::vector<Surface>& surfaces, const Eigen::Vector3d& centre,
                                              double min_area_m2) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double area = 0.0;
  for (const Surface& s : surfaces) {
    if (!s.floor) continue;
    const Eigen::Vector3d& n = s.geometry.normal;
    sum += (n.dot(centre - s.geometry.centroid) < 0 ? -s.geometry.area_m2 : s.geometry.area_m2) * n;
    area += s.geometry.area_m2;
  }
  if (area < min_area_m2 || sum.norm() < 1e-12) return std::nullopt;
  return sum.normalized();
}

/// Refines `up` by the near-horizontal triangles (floor-labelled ones first); returns whether
/// any refinement happened and whether the last one used the floor labels.
std::pair<bool, bool> refine_up(const std::vector<Surface>& surfaces, Eigen::Vector3d& up, const GravityOptions& o) {
  const double min_cos = cos_deg(o.prior_cone_deg);
  bool refined = false, by_floor = false;
  for (int i = 0; i < o.refine_iterations; ++i) {
    double area = 0.0;
    Eigen::Vector3d sum = agreeing_normal_sum(surfaces, up, min_cos, true, area);
    by_floor = area >= o.min_refine_area_m2;
    if (!by_floor) sum = agreeing_normal_sum(surfaces, up, min_cos, false, area);
    if (area < o.min_refine_area_m2 || sum.norm() < 1e-12) break;
    up = sum.normalized();
    refined = true;
  }
  return {refined, by_floor};
}

/// Up from the floor labels alone when the cameras' prior contradicts them: the labelled floor's
/// dominant normal (floor_label_up, then refined as any prior is: refine_up), taken
/// when at least twice as much floor-labelled area faces it (within floor_normal_deg) as faces
/// the prior. The level-x-axes prior assumes the camera turns about the vertical; one held
/// pitched down that pans about its own y axis (TUM fr1_rpy: 50 deg off) breaks it, and the
/// network's floor labels then lie far outside the refinement cone. nullopt: keep the prior.
std::optional<Eigen::Vector3d> floor_labels_over_prior(const std::vector<Surface>& surfaces, const Eigen::Vector3d& centre,
                                                       const Eigen::Vector3d& prior, const GravityOptions& o) {
  std::optional<Eigen::Vector3d> up = floor_label_up(surfaces, centre, o.min_refine_area_m2);
  if (!up) return std::nullopt;
  refine_up(surfaces, *up, o);
  double area_up = 0.0, area_prior = 0.0;
  agreeing_normal_sum(surfaces, *up, cos_deg(o.floor_normal_deg), true, area_up);
  agreeing_normal_sum(surfaces, prior, cos_deg(o.floor_normal_deg), true, area_prior);
  if (area_up < o.min_floor_area_m2 || area_up < 2.0 * area_prior) return std::nullopt;
  return up;
}

/// The lowest large near-horizontal surface below `reference_height` (see the header).
std::optional<double> floor_height(const std::vector<Surface>& surfaces, const Eigen::Vector3d& up,
                                   double reference_height, const GravityOptions& o) {
  const double min_cos = cos_deg(o.floor_normal_deg);
  std::vector<std::pair<double, double>> candidates;  // (height, area)
  double total = 0.0, lo = INFINITY, hi = -INFINITY;
  for (const Surface& s : surfaces) {
    if (std::abs(s.geometry.normal.dot(up)) < min_cos) continue;
    const double h = up.dot(s.geometry.centroid);
    if (h >= reference_height) continue;
    candidates.emplace_back(h, s.geometry.area_m2);
    total += s.geometry.area_m2;
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
  if (total < o.min_floor_area_m2) return std::nullopt;
  // A huge height range (stray vertices far away) widens the bins instead of allocating millions.
  constexpr double kMaxBins = 1 << 20;
  const double bin = std::max(o.floor_bin_m, (hi - lo) / kMaxBins);
  const size_t bins = static_cast<size_t>((hi - lo) / bin) + 1;
  std::vector<double> area(bins + 1, 0.0);
  for (const auto& [h, a] : candidates) area[std::min(bins - 1, static_cast<size_t>((h - lo) / bin))] += a;
  for (size_t b = 0; b < bins; ++b) {
    if (area[b] + area[b + 1] < o.min_floor_share * total) continue;
    // The median of the bin pair, then re-centred on a window around it (the pair may start
    // below the floor's peak).
    auto median_within = [&](double from, double to) {
      std::vector<std::pair<double, double>> in;
      for (const auto& c : candidates)
        if (c.first >= from && c.first < to) in.push_back(c);
      return weighted_quantile(std::move(in), 0.5);
    };
    const double first = median_within(lo + b * bin, lo + (b + 2) * bin);
    return median_within(first - bin, first + bin);
  }
  return std::nullopt;  // no height holds the share: no dominant floor
}

/// The floor plane's normal: an area-weighted least-squares plane through the centroids of the
/// near-horizontal triangles within floor_plane_band_m of the floor height (floor, rug, anything
/// lying on it), its normal turned to agree with `up`. nullopt when they cover less than
/// min_floor_area_m2 or do not span floor_plane_min_extent_m in both directions (a strip of
/// floor leaves the tilt about its axis undetermined).
std::optional<Eigen::Vector3d> floor_plane_normal(const std::vector<Surface>& surfaces, const Eigen::Vector3d& up,
                                                  double floor_height_m, const GravityOptions& o) {
  const double min_cos = cos_deg(o.floor_normal_deg);
  double area = 0.0;
  Eigen::Vector3d weighted_sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d weighted_outer = Eigen::Matrix3d::Zero();
  for (const Surface& s : surfaces) {
    const Eigen::Vector3d& c = s.geometry.centroid;
    if (std::abs(s.geometry.normal.dot(up)) < min_cos || std::abs(up.dot(c) - floor_height_m) > o.floor_plane_band_m)
      continue;
    area += s.geometry.area_m2;
    weighted_sum += s.geometry.area_m2 * c;
    weighted_outer += s.geometry.area_m2 * c * c.transpose();
  }
  if (area < o.min_floor_area_m2) return std::nullopt;
  const Eigen::Vector3d mean = weighted_sum / area;
  const Eigen::Matrix3d covariance = weighted_outer / area - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  // A uniform extent L has variance L^2 / 12.
  const double min_variance = o.floor_plane_min_extent_m * o.floor_plane_min_extent_m / 12.0;
  if (eigen.info() != Eigen::Success || eigen.eigenvalues()(1) < min_variance) return std::nullopt;
  const Eigen::Vector3d normal = eigen.eigenvectors().col(0);
  if (std::abs(normal.dot(up)) < min_cos) return std::nullopt;
  return normal.dot(up) < 0 ? Eigen::Vector3d(-normal) : normal;
}

Pose gravity_frame(const Eigen::Vector3d& up, const Eigen::Vector3d& origin) {
  Eigen::Vector3d x = Eigen::Vector3d::UnitX() - up.x() * up;
  if (x.norm() < 0.1) x = Eigen::Vector3d::UnitY() - up.y() * up;
  x.normalize();
  Pose T = Pose::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = up.cross(x);
  T.linear().col(2) = up;
  T.translation() = origin;
  return T;
}

/// Height of the ground under the frame origin when no floor was found.
double fallback_ground_height(const TriangleMesh& mesh, const Trajectory& trajectory, const Eigen::Vector3d& up) {
  double lowest = INFINITY;
  for (const auto& v : mesh.vertices.points)
    if (v.allFinite()) lowest = std::min(lowest, up.dot(v.cast<double>()));
  if (std::isfinite(lowest)) return lowest;
  for (const auto& p : trajectory) lowest = std::min(lowest, up.dot(p.T_world_camera.translation()));
  return std::isfinite(lowest) ? lowest : 0.0;
}

}  // namespace

TriangleGeometry triangle_geometry(const TriangleMesh& mesh, size_t t) {
  TriangleGeometry g;
  const auto& tri = mesh.triangles[t];
  const auto& p = mesh.vertices.points;
  if (tri[0] >= p.size() || tri[1] >= p.size() || tri[2] >= p.size()) return g;
  const Eigen::Vector3d a = p[tri[0]].cast<double>(), b = p[tri[1]].cast<double>(), c = p[tri[2]].cast<double>();
  const Eigen::Vector3d cross = (b - a).cross(c - a);
  const double length = cross.norm();
  if (!std::isfinite(length) || length <= 0.0) return g;
  g.normal = cross / length;
  g.centroid = (a + b + c) / 3.0;
  g.area_m2 = 0.5 * length;
  return g;
}

ClassId triangle_label(const TriangleMesh& mesh, size_t t) {
  const auto& labels = mesh.vertices.labels;
  const auto& tri = mesh.triangles[t];
  if (tri[0] >= labels.size() || tri[1] >= labels.size() || tri[2] >= labels.size()) return 0;
  const ClassId a = labels[tri[0]], b = labels[tri[1]], c = labels[tri[2]];
  return (b == c && a != b) ? b : a;  // a when it is shared or nothing is; else the b == c pair
}

double weighted_quantile(std::vector<std::pair<double, double>> value_weight, double q) {
  double total = 0.0;
  for (const auto& vw : value_weight) total += vw.second;
  if (value_weight.empty() || !(total > 0.0)) return 0.0;
  std::sort(value_weight.begin(), value_weight.end());
  const double target = std::clamp(q, 0.0, 1.0) * total;
  double cumulative = 0.0;
  for (const auto& [value, weight] : value_weight) {
    cumulative += weight;
    if (cumulative >= target) return value;
  }
  return value_weight.back().first;
}

GravityEstimate estimate_gravity(const TriangleMesh& mesh, const Trajectory& trajectory, const GravityOptions& options) {
  GravityEstimate e;
  const std::vector<Surface> surfaces = surfaces_of(mesh);
  const std::optional<Eigen::Vector3d> centre = mesh_centre(mesh);
  const std::optional<Eigen::Vector3d> from_trajectory = trajectory_up(trajectory, options.min_x_axis_spread);
  std::optional<Eigen::Vector3d> prior = from_trajectory;
  bool trajectory_prior = from_trajectory.has_value();
  if (prior && centre)
    if (const auto floor_up = floor_labels_over_prior(surfaces, *centre, *prior, options)) {
      prior = floor_up;
      trajectory_prior = false;
    }
  if (!prior && centre) prior = floor_label_up(surfaces, *centre, options.min_refine_area_m2);

  Eigen::Vector3d up = prior.value_or(Eigen::Vector3d::UnitZ());
  if (trajectory_prior) e.method = GravityMethod::kTrajectory;
  else if (prior) e.method = GravityMethod::kFloorLabels;
  // +z without anything to go by: not refined (in a y-up world its "horizontal" surfaces are walls).
  if (prior) {
    const auto [refined, by_floor] = refine_up(surfaces, up, options);
    if (trajectory_prior && refined)
      e.method = by_floor ? GravityMethod::kTrajectoryFloorLabels : GravityMethod::kTrajectoryHorizontal;
  }

  // Floor candidates lie below the cameras (the ceiling is above them).
  double reference_height = centre ? up.dot(*centre) : 0.0;
  if (!trajectory.empty()) {
    double sum = 0.0;
    for (const auto& p : trajectory) sum += up.dot(p.T_world_camera.translation());
    if (std::isfinite(sum)) reference_height = sum / static_cast<double>(trajectory.size());
  }
  if (const auto h = floor_height(surfaces, up, reference_height, options)) {
    e.floor_found = true;
    e.floor_height_m = *h;
    // Gravity is perpendicular to the floor: its plane refines up (the horizontal surfaces'
    // mean normal mixes in table tops, which a drifting map tilts against the floor). Not
    // without a prior: +z's "floor" may be a wall.
    for (int i = 0; prior && i < options.refine_iterations; ++i) {
      const auto normal = floor_plane_normal(surfaces, up, e.floor_height_m, options);
      if (!normal) break;
      up = *normal;
      e.up_from_floor_plane = true;
      if (const auto refined_h = floor_height(surfaces, up, reference_height, options)) e.floor_height_m = *refined_h;
    }
  }
  e.up_W = up;
  if (prior) e.prior_to_up_deg = std::acos(std::clamp(prior->dot(up), -1.0, 1.0)) * 180.0 / std::numbers::pi;

  Eigen::Vector3d origin = centre.value_or(Eigen::Vector3d::Zero());
  if (!centre && !trajectory.empty()) {
    origin.setZero();
    for (const auto& p : trajectory) origin += p.T_world_camera.translation() / static_cast<double>(trajectory.size());
  }
  const double ground = e.floor_found ? e.floor_height_m : fallback_ground_height(mesh, trajectory, up);
  e.T_W_G = gravity_frame(up, origin + (ground - up.dot(origin)) * up);
  return e;
}

}  // namespace semap
