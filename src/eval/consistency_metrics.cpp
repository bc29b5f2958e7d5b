#include "semap/eval/consistency_metrics.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "core/paths.hpp"
#include "semap/core/error.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"

namespace semap {
namespace {

/// Area sums of one structural class while the triangles are visited.
struct AgreementSum {
  double area = 0.0, agreeing = 0.0, facing = 0.0;
  ClassAgreement finish(double mesh_area) const {
    ClassAgreement a;
    a.area_m2 = area;
    if (mesh_area > 0.0) a.area_share = area / mesh_area;
    if (area > 0.0) a.agreement = agreeing / area, a.facing_agreement = facing / area;
    return a;
  }
};

nlohmann::json json_of(const ClassAgreement& a, bool facing) {
  nlohmann::json j = {{"area_m2", a.area_m2}, {"area_share", a.area_share}};
  // No area of the class: nothing to agree with (null, not 0 or 1).
  j["agreement"] = a.area_m2 > 0.0 ? nlohmann::json(a.agreement) : nlohmann::json(nullptr);
  if (facing) j["facing_agreement"] = a.area_m2 > 0.0 ? nlohmann::json(a.facing_agreement) : nlohmann::json(nullptr);
  return j;
}

nlohmann::json optional_json(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

}  // namespace

SemanticConsistency evaluate_consistency(const TriangleMesh& mesh, const Trajectory& trajectory,
                                         const ConsistencyOptions& options) {
  SemanticConsistency c;
  c.agreement_deg = options.agreement_deg;
  c.gravity = estimate_gravity(mesh, trajectory, options.gravity);
  const Eigen::Vector3d& up = c.gravity.up_W;
  // Floor/ceiling: |cos(normal, up)| >= cos(tol). Wall: |cos(normal, up)| <= sin(tol).
  const double tolerance_rad = options.agreement_deg * std::numbers::pi / 180.0;
  const double vertical_cos = std::cos(tolerance_rad), horizontal_cos = std::sin(tolerance_rad);

  std::array<double, 256> class_area{};
  AgreementSum floor, wall, ceiling;
  std::vector<std::pair<double, double>> floor_heights;  // (height along up, area)
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const TriangleGeometry g = triangle_geometry(mesh, t);
    if (!(g.area_m2 > 0.0)) continue;
    ++c.triangles;
    c.mesh_area_m2 += g.area_m2;
    const ClassId label = triangle_label(mesh, t);
    class_area[label] += g.area_m2;
    const double cos_up = g.normal.dot(up);
    if (label == id(Label::kFloor)) {
      floor.area += g.area_m2;
      if (std::abs(cos_up) >= vertical_cos) floor.agreeing += g.area_m2;
      if (cos_up >= vertical_cos) floor.facing += g.area_m2;
      floor_heights.emplace_back(up.dot(g.centroid), g.area_m2);
    } else if (label == id(Label::kCeiling)) {
      ceiling.area += g.area_m2;
      if (std::abs(cos_up) >= vertical_cos) ceiling.agreeing += g.area_m2;
      if (-cos_up >= vertical_cos) ceiling.facing += g.area_m2;
    } else if (label == id(Label::kWall)) {
      wall.area += g.area_m2;
      if (std::abs(cos_up) <= horizontal_cos) wall.agreeing += g.area_m2, wall.facing += g.area_m2;
    }
  }
  if (c.mesh_area_m2 > 0.0) c.labelled_area_share = 1.0 - class_area[0] / c.mesh_area_m2;
  c.floor = floor.finish(c.mesh_area_m2);
  c.wall = wall.finish(c.mesh_area_m2);
  c.ceiling = ceiling.finish(c.mesh_area_m2);

  for (int k = 1; k < 256; ++k)
    if (class_area[k] > 0.0)
      c.classes.push_back({static_cast<ClassId>(k), class_area[k], class_area[k] / c.mesh_area_m2});
  std::stable_sort(c.classes.begin(), c.classes.end(),
                   [](const ClassArea& a, const ClassArea& b) { return a.area_m2 > b.area_m2; });
  if (c.classes.size() > static_cast<size_t>(std::max(0, options.top_classes))) c.classes.resize(options.top_classes);

  if (!floor_heights.empty()) {
    c.floor_height_low_m = weighted_quantile(floor_heights, options.thickness_low_quantile);
    c.floor_height_high_m = weighted_quantile(std::move(floor_heights), options.thickness_high_quantile);
    c.floor_thickness_m = *c.floor_height_high_m - *c.floor_height_low_m;
  }
  return c;
}

SemanticConsistency evaluate_consistency_folder(const std::filesystem::path& out_dir, const ConsistencyOptions& options) {
  std::error_code ec;
  if (!std::filesystem::is_directory(out_dir, ec))
    throw Error(out_dir, "is " + describe_path(out_dir) + ", expected a semap run's output folder");
  const std::filesystem::path mesh_path = out_dir / "mesh.ply";
  require_regular_file(mesh_path, "mesh");
  const TriangleMesh mesh = read_ply(mesh_path);
  if (mesh.triangles.empty()) throw Error(mesh_path, "the mesh has no triangles");
  const std::filesystem::path trajectory_path = out_dir / "trajectory.txt";
  Trajectory trajectory;
  if (std::filesystem::exists(std::filesystem::symlink_status(trajectory_path, ec)))
    trajectory = read_tum_trajectory(trajectory_path);
  return evaluate_consistency(mesh, trajectory, options);
}

nlohmann::json to_json(const GravityEstimate& g) {
  return {{"up", {g.up_W.x(), g.up_W.y(), g.up_W.z()}},
          {"method", std::string(enum_name(kGravityMethodNames, g.method))},
          {"floor_found", g.floor_found},
          {"floor_height_m", g.floor_found ? nlohmann::json(g.floor_height_m) : nlohmann::json(nullptr)},
          {"prior_to_up_deg", g.prior_to_up_deg},
          {"up_from_floor_plane", g.up_from_floor_plane}};
}

nlohmann::json to_json(const SemanticConsistency& c) {
  nlohmann::json classes = nlohmann::json::object();
  for (const ClassArea& a : c.classes) classes[std::string(class_name(a.class_id))] = a.area_share;
  return {{"triangles", c.triangles},
          {"mesh_area_m2", c.mesh_area_m2},
          {"labelled_area_share", c.labelled_area_share},
          {"class_area_share", classes},
          {"agreement_deg", c.agreement_deg},
          {"floor", json_of(c.floor, true)},
          {"wall", json_of(c.wall, false)},
          {"ceiling", json_of(c.ceiling, true)},
          {"floor_thickness_m", optional_json(c.floor_thickness_m)},
          {"floor_height_low_m", optional_json(c.floor_height_low_m)},
          {"floor_height_high_m", optional_json(c.floor_height_high_m)},
          {"gravity", to_json(c.gravity)}};
}

}  // namespace semap
