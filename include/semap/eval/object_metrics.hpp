#pragma once
// Object-map evaluation (METHODS.md C6, D): objects per class against ground truth, weighted
// overlap WOv, precision/recall of instances at 3D IoU thresholds.
//
// Every object (GT or map) is a set of surface points. IoU(G, S) is measured on the surfaces,
// with a distance tolerance d (match_distance_m, default 2 cm, one map voxel), like the semantic
// mIoU and like reconstruction benchmarks' precision/recall at a threshold (Tanks and Temples):
//   recall    r = fraction of G's points within d of a point of S,
//   precision p = fraction of S's points within d of a point of G,
//   IoU       = p r / (p + r - p r)   (TP / (TP + FP + FN) with FP = TP (1/p - 1), FN = TP (1/r - 1)).
// It depends only on the two sets (not on the other objects, as C6 defines it), not on their
// sampling densities nor on any grid; a map within d of the truth scores 1, points farther than d
// from G count against precision, parts of G with no point of S nearer than d against recall.
// |G_i| (the weight in WOv) is G_i's number of occupied voxel_size_m voxels: its surface area,
// whatever its sampling density.
//  - WOv = sum_i |G_i| max_j IoU(G_i, S_j) / sum_i |G_i| over GT objects G_i and ALL map
//    objects S_j (class-agnostic, exactly C6). wov_same_class restricts j to S_j of G_i's class.
//  - wov_voxel: the same sum with IoU = |A n B| / |A u B| of the occupied voxel sets (the
//    figure earlier versions reported). It depends on the grid: a surface a few millimetres off
//    a voxel border puts the map's points in the next layer (a planar table top 3 mm above the
//    truth scored 0.45), so it is reported for comparison only.
//  - Precision/recall at threshold t: candidate pairs (G_i, S_j) of the SAME class with
//    IoU >= t, taken greedily by descending IoU, each object used at most once. precision =
//    matches / #map objects, recall = matches / #GT objects (0 when the denominator is 0).
// GT sources: gt_points.ply -> one object per instance id > 0 (its points; class = majority
// label of the points). scene.json -> the surfaces of each object's primitive boxes
// ("primitives" bounds; the object's "obb" when absent), sampled at voxel_size/2: the whole
// closed shell, including faces hidden by contact, so a perfect map scores below 1 there;
// gt_points.ply (only observed surfaces) is the preferred ground truth.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "semap/core/labels.hpp"
#include "semap/core/point_cloud.hpp"

namespace semap {

struct ObjectEvalOptions {
  double match_distance_m = 0.02;  ///< d: a point lies on a surface when this close to it (m)
  double voxel_size_m = 0.02;      ///< grid of the GT weights |G_i| and of wov_voxel (m)
  std::vector<double> iou_thresholds{0.25, 0.5};  ///< precision/recall thresholds
};

/// One object to evaluate: id (GT instance id or map object id), class, surface points.
struct EvalObject {
  uint32_t id = 0;
  ClassId class_id = 0;
  std::vector<Eigen::Vector3f> points;
};

struct ObjectClassCount {
  ClassId class_id = 0;
  size_t gt = 0, map = 0;
};

struct ObjectMatchStats {
  double iou_threshold = 0.0;
  size_t true_positives = 0;
  double precision = 0.0, recall = 0.0;
};

struct GtObjectScore {
  uint32_t gt_id = 0;
  ClassId class_id = 0;
  size_t voxels = 0;             ///< |G_i|
  double best_iou = 0.0;         ///< max_j IoU(G_i, S_j), any class
  int64_t best_map_id = -1;      ///< argmax (-1: no overlap at all)
  double best_precision = 0.0;   ///< p and r of that best pair
  double best_recall = 0.0;
  double best_iou_same_class = 0.0;
};

struct ObjectEvaluation {
  size_t gt_objects = 0, map_objects = 0;
  std::vector<ObjectClassCount> counts;  ///< every class present on either side, ascending
  double wov = 0.0;                      ///< C6 weighted overlap, class-agnostic
  double wov_same_class = 0.0;
  double wov_voxel = 0.0;  ///< WOv with voxel-set IoU (grid-dependent, for comparison)
  std::vector<ObjectMatchStats> matches;  ///< one per options.iou_thresholds
  std::vector<GtObjectScore> per_gt;
};

ObjectEvaluation evaluate_objects(const std::vector<EvalObject>& gt, const std::vector<EvalObject>& map,
                                  const ObjectEvalOptions& options = {});

/// One object per instance id > 0 of a labelled, instanced GT cloud (gt_points.ply).
std::vector<EvalObject> gt_objects_from_points(const PointCloud& gt_points);
/// Objects of a synthetic scene.json, sampled on their box surfaces every `spacing_m`.
std::vector<EvalObject> gt_objects_from_scene_json(const std::filesystem::path& scene_json,
                                                   double spacing_m);
/// Dispatches on the extension: .json -> scene.json, .ply -> gt_points.ply.
std::vector<EvalObject> load_gt_objects(const std::filesystem::path& path, double spacing_m);
/// Reads objects.json and every object's points_file (relative to the json's folder). An
/// object whose points_file is absent while its point_count is 0 has no points; otherwise a
/// missing file is a semap::Error naming it.
std::vector<EvalObject> load_map_objects(const std::filesystem::path& objects_json);

ObjectEvaluation evaluate_object_files(const std::filesystem::path& gt_path,
                                       const std::filesystem::path& objects_json,
                                       const ObjectEvalOptions& options = {});

nlohmann::json to_json(const ObjectEvaluation& evaluation);

}  // namespace semap
