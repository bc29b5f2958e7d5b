#pragma once
// Dense semantic map evaluation (METHODS.md D): per-class IoU / mIoU of map-vertex labels
// against labelled ground-truth points, surface error and completeness.
//
// Label transfer is by nearest neighbour in BOTH directions and the two are merged into one
// confusion matrix:
//  - GT -> map: each labelled GT point (label != 0) takes the label of its nearest map vertex
//    within max_distance_m; no vertex that close, or an unlabelled vertex, is a miss
//    (false negative of the GT class). Measures recall.
//  - map -> GT: each labelled map vertex (label != 0) takes the GT label of its nearest GT
//    point within max_distance_m; a GT point labelled 0 means "ignore" (ScanNet), no GT point
//    that close is a false positive of the map class (unless
//    unmatched_map_vertices_are_false_positives is off). Measures precision.
//  - Each direction is normalised to total weight 1/2 (every GT entry weighs 0.5/N_gt, every
//    map entry 0.5/N_map), so neither side's sampling density dominates; then
//    IoU_c = C[c][c] / (row_c + col_c - C[c][c]). For a map that is a relabelled copy of the
//    GT points this equals the plain point-wise IoU.
// Classes whose union weight is 0 (absent from both GT and map) are excluded from the mIoU.
#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "semap/core/labels.hpp"
#include "semap/core/point_cloud.hpp"

namespace semap {

struct SemanticEvalOptions {
  double max_distance_m = 0.05;           ///< label-transfer neighbour distance (m)
  double completeness_distance_m = 0.02;  ///< GT point counts as covered within this (m)
  bool unmatched_map_vertices_are_false_positives = true;  ///< map vertex far from any GT
};

struct ClassIoU {
  ClassId class_id = 0;
  double iou = 0.0;
  double intersection = 0.0, uni = 0.0;  ///< normalised confusion weights
  size_t gt_points = 0;                  ///< labelled GT points of this class
  size_t map_vertices = 0;               ///< map vertices labelled with this class
  double recall = 0.0;                   ///< GT->map: fraction of this class' GT points correct
  double precision = 0.0;                ///< map->GT: fraction of its evaluated vertices correct
};

struct SemanticEvaluation {
  std::vector<ClassIoU> classes;  ///< classes with a non-empty union, ascending id
  double miou = 0.0;              ///< mean IoU over `classes` (0 when empty)
  /// Distance of each map vertex to its nearest GT point. GT points sample the surfaces
  /// densely (~1 cm), so this approximates the point-to-surface distance (it overestimates
  /// it by at most about half the GT spacing).
  double surface_error_mean_m = 0.0, surface_error_median_m = 0.0;
  double completeness = 0.0;  ///< fraction of GT points with a map vertex within the distance
  size_t gt_points = 0, gt_points_labelled = 0, gt_points_missed = 0;
  size_t map_vertices = 0, map_vertices_labelled = 0, map_vertices_off_surface = 0;
  /// Points with a NaN/Inf coordinate, excluded from everything above (counted, not fatal:
  /// one broken vertex must not turn the surface error into inf).
  size_t gt_points_non_finite = 0, map_vertices_non_finite = 0;
  /// Combined normalised confusion, (kNumClasses+1)^2 row-major: rows = GT class (row
  /// kNumClasses: "no GT surface nearby"), columns = map class (column kNumClasses: "no map
  /// vertex nearby"). Row 0 (GT unlabelled) stays empty.
  std::vector<double> confusion;
};

/// Both clouds need finite points; `gt` needs labels (throws semap::Error otherwise). Points
/// with a non-finite coordinate are dropped first and counted. A map without labels counts as
/// entirely unlabelled (every GT class gets IoU 0).
SemanticEvaluation evaluate_semantic(const PointCloud& gt, const PointCloud& map_vertices,
                                     const SemanticEvalOptions& options = {});
/// Reads gt_points.ply and the map mesh/cloud PLY (its vertices), then evaluate_semantic.
SemanticEvaluation evaluate_semantic_files(const std::filesystem::path& gt_ply,
                                           const std::filesystem::path& map_ply,
                                           const SemanticEvalOptions& options = {});

nlohmann::json to_json(const SemanticEvaluation& evaluation);

}  // namespace semap
