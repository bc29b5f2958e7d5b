// `semap eval ate|semantic|objects`: the metrics of METHODS.md D on result files;
// `semap eval consistency OUT`: the ground-truth-free semantic check of a run's output (issue 38).
// --json prints exactly one JSON object on stdout; otherwise an aligned table.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include <new>
#include <nlohmann/json.hpp>

#include "apps/semap/commands.hpp"
#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "semap/eval/consistency_metrics.hpp"
#include "semap/eval/object_metrics.hpp"
#include "semap/eval/semantic_metrics.hpp"
#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/trajectory_io.hpp"

namespace semap::app {

namespace {

struct EvalOptions {
  std::string gt, est, map, out;
  bool json = false;
  double max_dt = 0.02;
  double delta_s = 1.0;
  SemanticEvalOptions semantic;
  ObjectEvalOptions objects;
  ConsistencyOptions consistency;
};

void require_file(const std::string& path, const char* flag) {
  if (path.empty()) throw Error(flag, "missing");
  require_regular_file(path, std::string(flag) + " file");
}

/// Runs one eval command; an error other than semap::Error (std::bad_alloc, a library's
/// std::exception) names the command's input files instead of reaching main bare (issue 44,
/// class 8: "std::bad_alloc" without a file name).
int naming_inputs(const EvalOptions& o, int (*command)(const EvalOptions&)) {
  try {
    return command(o);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    std::string inputs;
    for (const std::string* path : {&o.gt, &o.est, &o.map, &o.out})
      if (!path->empty()) inputs += (inputs.empty() ? "" : ", ") + *path;
    const bool memory = dynamic_cast<const std::bad_alloc*>(&e) != nullptr;
    throw Error(inputs, memory ? "out of memory evaluating these files" : message_text(e.what(), 2000));
  }
}

void print_json(const nlohmann::json& j) { std::printf("%s\n", j.dump(2).c_str()); }

int run_ate(const EvalOptions& o) {
  require_file(o.gt, "--gt");
  require_file(o.est, "--est");
  const Trajectory gt = read_tum_trajectory(o.gt);
  const Trajectory est = read_tum_trajectory(o.est);
  if (gt.empty()) throw Error(o.gt, "trajectory has no poses");
  if (est.empty()) throw Error(o.est, "trajectory has no poses");
  const AteResult ate = compute_ate(gt, est, o.max_dt);
  const RpeResult rpe = compute_rpe(gt, est, o.delta_s, o.max_dt);
  if (o.json) {
    print_json({{"gt", o.gt}, {"est", o.est}, {"gt_poses", gt.size()}, {"est_poses", est.size()},
                {"max_dt_s", o.max_dt}, {"ate", to_json(ate)},
                {"rpe", [&] { auto j = to_json(rpe); j["delta_s"] = o.delta_s; return j; }()}});
    return 0;
  }
  std::printf("trajectory   %s vs %s (%zu / %zu poses, %zu associated)\n", o.est.c_str(), o.gt.c_str(),
              est.size(), gt.size(), ate.matched);
  std::printf("%-26s %12s\n", "metric", "value");
  std::printf("%-26s %12.6f\n", "ATE rmse [m]", ate.rmse);
  std::printf("%-26s %12.6f\n", "ATE mean [m]", ate.mean);
  std::printf("%-26s %12.6f\n", "ATE median [m]", ate.median);
  std::printf("%-26s %12.6f\n", "ATE max [m]", ate.max);
  if (rpe.pairs == 0) {
    std::printf("%-26s %12s  (%s)\n", "RPE", "n/a", rpe.no_pairs_reason.c_str());
  } else {
    std::printf("%-26s %12.6f\n", "RPE trans rmse [m/s]", rpe.trans_rmse_m_per_s);
    std::printf("%-26s %12.6f\n", "RPE rot rmse [deg/s]", rpe.rot_rmse_deg_per_s);
  }
  std::printf("%-26s %12zu\n", "RPE pairs", rpe.pairs);
  return 0;
}

int run_semantic(const EvalOptions& o) {
  require_file(o.gt, "--gt");
  require_file(o.map, "--map");
  const SemanticEvaluation e = evaluate_semantic_files(o.gt, o.map, o.semantic);
  if (o.json) {
    nlohmann::json j = to_json(e);
    j["gt"] = o.gt;
    j["map"] = o.map;
    j["max_distance_m"] = o.semantic.max_distance_m;
    j["completeness_distance_m"] = o.semantic.completeness_distance_m;
    print_json(j);
    return 0;
  }
  std::printf("semantic     %s vs %s (%zu map vertices, %zu GT points)\n", o.map.c_str(), o.gt.c_str(),
              e.map_vertices, e.gt_points);
  if (e.map_vertices_non_finite + e.gt_points_non_finite > 0)
    std::printf("excluded     %zu map vertices and %zu GT points with NaN/Inf coordinates\n", e.map_vertices_non_finite,
                e.gt_points_non_finite);
  std::printf("%-14s %8s %10s %8s %10s %12s\n", "class", "IoU", "precision", "recall", "GT points", "map vertices");
  for (const auto& c : e.classes)
    std::printf("%-14s %8.4f %10.4f %8.4f %10zu %12zu\n", std::string(class_name(c.class_id)).c_str(), c.iou,
                c.precision, c.recall, c.gt_points, c.map_vertices);
  std::printf("%-14s %8.4f  (%zu classes)\n", "mIoU", e.miou, e.classes.size());
  std::printf("surface error  mean %.4f m, median %.4f m\n", e.surface_error_mean_m, e.surface_error_median_m);
  std::printf("completeness   %.4f (GT points with a map vertex within %.3f m)\n", e.completeness,
              o.semantic.completeness_distance_m);
  return 0;
}

int run_objects(const EvalOptions& o) {
  require_file(o.gt, "--gt");
  require_file(o.map, "--map");
  const ObjectEvaluation e = evaluate_object_files(o.gt, o.map, o.objects);
  if (o.json) {
    nlohmann::json j = to_json(e);
    j["gt"] = o.gt;
    j["map"] = o.map;
    j["voxel_size_m"] = o.objects.voxel_size_m;
    j["match_distance_m"] = o.objects.match_distance_m;
    print_json(j);
    return 0;
  }
  std::printf("objects      %s vs %s (%zu map objects, %zu GT objects)\n", o.map.c_str(), o.gt.c_str(),
              e.map_objects, e.gt_objects);
  std::printf("%-14s %6s %6s\n", "class", "GT", "map");
  for (const auto& c : e.counts)
    std::printf("%-14s %6zu %6zu\n", std::string(class_name(c.class_id)).c_str(), c.gt, c.map);
  std::printf("WOv            %.4f (same class only: %.4f; voxel-set IoU: %.4f)\n", e.wov, e.wov_same_class,
              e.wov_voxel);
  for (const auto& m : e.matches)
    std::printf("IoU >= %.2f    precision %.4f  recall %.4f  (%zu matched)\n", m.iou_threshold, m.precision,
                m.recall, m.true_positives);
  return 0;
}

/// "0.1234", or "n/a" when the class has no area.
std::string share_text(const ClassAgreement& a, double share) {
  if (!(a.area_m2 > 0.0)) return "n/a";
  char text[32];
  std::snprintf(text, sizeof text, "%.4f", share);
  return text;
}

int run_consistency(const EvalOptions& o) {
  const SemanticConsistency c = evaluate_consistency_folder(o.out, o.consistency);
  if (o.json) {
    nlohmann::json j = to_json(c);
    j["out"] = o.out;
    print_json(j);
    return 0;
  }
  const GravityEstimate& g = c.gravity;
  const std::string floor = g.floor_found ? "floor at " + compact_number(g.floor_height_m) + " m" : "no floor found";
  std::printf("consistency  %s (%zu triangles, %.2f m^2)\n", o.out.c_str(), c.triangles, c.mesh_area_m2);
  std::printf("gravity      up (%.4f %.4f %.4f) from %s; %s\n", g.up_W.x(), g.up_W.y(), g.up_W.z(),
              std::string(enum_name(kGravityMethodNames, g.method)).c_str(),
              floor.c_str());
  std::printf("%-22s %8.4f\n", "labelled area share", c.labelled_area_share);
  for (const auto& a : c.classes)
    std::printf("  %-20s %8.4f\n", std::string(class_name(a.class_id)).c_str(), a.area_share);
  std::printf("normals within %g deg  %-10s %-10s %s\n", c.agreement_deg, "share", "agreement", "as wound");
  std::printf("  %-20s %-10.4f %-10s %s (up)\n", "floor (horizontal)", c.floor.area_share,
              share_text(c.floor, c.floor.agreement).c_str(), share_text(c.floor, c.floor.facing_agreement).c_str());
  std::printf("  %-20s %-10.4f %-10s %s (down)\n", "ceiling (horizontal)", c.ceiling.area_share,
              share_text(c.ceiling, c.ceiling.agreement).c_str(),
              share_text(c.ceiling, c.ceiling.facing_agreement).c_str());
  std::printf("  %-20s %-10.4f %s\n", "wall (vertical)", c.wall.area_share, share_text(c.wall, c.wall.agreement).c_str());
  if (c.floor_thickness_m)
    std::printf("%-22s %8.4f m (heights %.3f .. %.3f m)\n", "floor thickness", *c.floor_thickness_m,
                *c.floor_height_low_m, *c.floor_height_high_m);
  else
    std::printf("%-22s %8s (no floor-labelled area)\n", "floor thickness", "n/a");
  return 0;
}

}  // namespace

void add_eval_command(CLI::App& app, CommandRunner& run) {
  auto* cmd = app.add_subcommand(
      "eval", "Evaluate results: trajectory (ATE/RPE), semantic mesh (mIoU), object map (WOv, P/R), consistency (no GT)");
  cmd->require_subcommand(1);
  auto opt = std::make_shared<EvalOptions>();

  auto* ate = cmd->add_subcommand("ate", "ATE RMSE after SE(3) alignment + RPE (TUM benchmark definitions)");
  ate->add_option("--gt", opt->gt, "ground-truth TUM trajectory")->required();
  ate->add_option("--est", opt->est, "estimated TUM trajectory")->required();
  ate->add_option("--max-dt", opt->max_dt, "max timestamp difference for association [s]")
      ->check(finite_in(1e-6, 10.0))
      ->capture_default_str();
  ate->add_option("--delta", opt->delta_s, "RPE time delta [s]")->check(finite_in(1e-3, 1e6))->capture_default_str();
  ate->add_flag("--json", opt->json, "print one JSON object");
  ate->callback([&run, opt] { run = [opt] { return naming_inputs(*opt, run_ate); }; });

  auto* sem = cmd->add_subcommand("semantic", "Per-class IoU / mIoU, surface error, completeness of a labelled mesh");
  sem->add_option("--gt", opt->gt, "gt_points.ply (x y z label [instance])")->required();
  sem->add_option("--map", opt->map, "labelled mesh or point cloud PLY")->required();
  sem->add_option("--max-dist", opt->semantic.max_distance_m, "label-transfer neighbour distance [m]")
      ->check(finite_in(1e-4, 10.0))
      ->capture_default_str();
  sem->add_option("--completeness-dist", opt->semantic.completeness_distance_m,
                  "a GT point is covered by a map vertex within this [m]")
      ->check(finite_in(1e-4, 10.0))
      ->capture_default_str();
  sem->add_flag("--json", opt->json, "print one JSON object");
  sem->callback([&run, opt] { run = [opt] { return naming_inputs(*opt, run_semantic); }; });

  auto* obj = cmd->add_subcommand("objects", "Objects per class, WOv, precision/recall at 3D IoU 0.25/0.5");
  obj->add_option("--gt", opt->gt, "scene.json or gt_points.ply")->required();
  obj->add_option("--map", opt->map, "objects.json")->required();
  obj->add_option("--match-dist", opt->objects.match_distance_m,
                  "a point lies on a surface within this distance (surface IoU) [m]")
      ->check(finite_in(1e-4, 1.0))
      ->capture_default_str();
  obj->add_option("--voxel", opt->objects.voxel_size_m, "voxel size of the GT weights and of wov_voxel [m]")
      ->check(finite_in(1e-3, 1.0))
      ->capture_default_str();
  obj->add_flag("--json", opt->json, "print one JSON object");
  obj->callback([&run, opt] { run = [opt] { return naming_inputs(*opt, run_objects); }; });

  auto* con = cmd->add_subcommand("consistency",
                                  "Without ground truth: labelled area share, floor/wall/ceiling normals against "
                                  "gravity, floor thickness of a run's OUT/mesh.ply (+ trajectory.txt)");
  con->add_option("OUT", opt->out, "output folder of semap run / demo")->required();
  con->add_option("--agreement-deg", opt->consistency.agreement_deg,
                  "floor/ceiling normal within this of vertical, wall normal within this of horizontal [deg]")
      ->check(finite_in(0.1, 89.0))
      ->capture_default_str();
  con->add_flag("--json", opt->json, "print one JSON object");
  con->callback([&run, opt] { run = [opt] { return naming_inputs(*opt, run_consistency); }; });
}

}  // namespace semap::app
