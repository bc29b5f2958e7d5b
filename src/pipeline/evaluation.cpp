#include "semap/pipeline/evaluation.hpp"

#include <spdlog/spdlog.h>

#include "semap/core/error.hpp"
#include "semap/io/ply_io.hpp"

namespace semap {
namespace {

std::vector<EvalObject> aligned_objects(const std::vector<ObjectSummary>& objects, const Eigen::Affine3f& T_gt_map) {
  std::vector<EvalObject> out;
  for (const ObjectSummary& o : objects) {
    EvalObject e{o.id, o.class_id, o.points};
    for (auto& p : e.points) p = T_gt_map * p;
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace

Evaluation evaluate_run(const DatasetReader& dataset, const MapOutputs& outputs, bool poses_given) {
  Evaluation evaluation;
  Pose T_gt_map = Pose::Identity();
  if (!poses_given && dataset.has_ground_truth()) {
    try {
      const Trajectory gt = dataset.ground_truth();
      evaluation.ate = compute_ate(gt, outputs.trajectory);
      evaluation.rpe = compute_rpe(gt, outputs.trajectory);
      T_gt_map = evaluation.ate->T_gt_est;
    } catch (const Error& e) {
      evaluation.note = std::string("trajectory evaluation skipped: ") + e.what();
      spdlog::warn("{}", evaluation.note);
    }
  }
  const auto gt_points = dataset.root() / "gt_points.ply";
  if (!std::filesystem::is_regular_file(gt_points)) return evaluation;
  const TriangleMesh gt = read_ply(gt_points);
  const Eigen::Affine3f T = T_gt_map.cast<float>();
  if (!outputs.mesh.vertices.empty()) {
    PointCloud aligned = outputs.mesh.vertices;
    for (auto& p : aligned.points) p = T * p;
    evaluation.semantic = evaluate_semantic(gt.vertices, aligned);
  }
  evaluation.objects = evaluate_objects(gt_objects_from_points(gt.vertices), aligned_objects(outputs.objects, T));
  return evaluation;
}

nlohmann::json to_json(const Evaluation& evaluation) {
  nlohmann::json j = nlohmann::json::object();
  if (evaluation.ate) j["ate"] = to_json(*evaluation.ate);
  if (evaluation.rpe) j["rpe"] = to_json(*evaluation.rpe);
  if (evaluation.semantic) j["semantic"] = to_json(*evaluation.semantic);
  if (evaluation.objects) j["objects"] = to_json(*evaluation.objects);
  if (!evaluation.note.empty()) j["note"] = evaluation.note;
  return j;
}

}  // namespace semap
