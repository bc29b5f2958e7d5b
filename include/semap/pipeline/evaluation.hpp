#pragma once
// Evaluation of a run against the dataset's ground truth: a separate step after mapping
// (the CLI calls it; mapping never reads ground truth).
#include <optional>

#include "semap/eval/object_metrics.hpp"
#include "semap/eval/semantic_metrics.hpp"
#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/dataset.hpp"
#include "semap/pipeline/outputs.hpp"

namespace semap {

struct Evaluation {
  std::optional<AteResult> ate;  ///< tracked runs with a ground-truth trajectory
  std::optional<RpeResult> rpe;
  std::optional<SemanticEvaluation> semantic;  ///< datasets with gt_points.ply (synthetic)
  std::optional<ObjectEvaluation> objects;
  std::string note;  ///< why a figure is missing (e.g. too few associated poses)
};

/// The map lives in the tracker's world (first camera); it is moved into the ground-truth world
/// by the ATE alignment (Horn/Umeyama) before the mesh and the objects are compared, as the TUM
/// benchmark aligns. `poses_given`: the trajectory is the ground truth itself (no ATE).
Evaluation evaluate_run(const DatasetReader& dataset, const MapOutputs& outputs, bool poses_given);

nlohmann::json to_json(const Evaluation& evaluation);

}  // namespace semap
