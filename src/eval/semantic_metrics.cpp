#include "semap/eval/semantic_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "semap/core/error.hpp"
#include "core/statistics.hpp"
#include "eval/nearest_neighbors.hpp"
#include "semap/io/ply_io.hpp"

namespace semap {
namespace {

constexpr int kNone = kNumClasses;  // "no GT surface" row / "no map vertex" column
constexpr int kSize = kNumClasses + 1;


ClassId checked_label(ClassId c, const char* which) {
  if (c >= kNumClasses) throw Error(which, "label " + std::to_string(c) + " is not a project class id");
  return c;
}

/// `cloud` without its points that have a NaN/Inf coordinate; `dropped` counts them.
PointCloud finite_points(const PointCloud& cloud, size_t& dropped) {
  dropped = 0;
  for (const auto& p : cloud.points) dropped += !p.allFinite();
  if (dropped == 0 || !cloud.consistent()) return cloud;
  PointCloud kept;
  for (size_t i = 0; i < cloud.size(); ++i)
    if (cloud.points[i].allFinite()) kept.push_back_from(cloud, i);
  return kept;
}

}  // namespace

SemanticEvaluation evaluate_semantic(const PointCloud& gt_all, const PointCloud& map_all,
                                     const SemanticEvalOptions& options) {
  size_t gt_dropped = 0, map_dropped = 0;
  const PointCloud gt = finite_points(gt_all, gt_dropped);
  const PointCloud map = finite_points(map_all, map_dropped);
  if (gt.empty()) throw Error("ground truth", gt_dropped ? "no finite points (all have NaN/Inf coordinates)" : "no points");
  if (map.empty() && map_dropped) throw Error("map", "no finite vertices (all have NaN/Inf coordinates)");
  if (!gt.has_labels() || gt.labels.size() != gt.size())
    throw Error("ground truth", "points carry no 'label' property");
  if (!(options.max_distance_m > 0.0) || !(options.completeness_distance_m > 0.0))
    throw Error("semantic eval", "distances must be > 0");
  const bool map_labelled = map.has_labels() && map.labels.size() == map.size();

  SemanticEvaluation result;
  result.gt_points = gt.size();
  result.map_vertices = map.size();
  result.gt_points_non_finite = gt_dropped;
  result.map_vertices_non_finite = map_dropped;

  const eval_detail::NearestNeighborIndex gt_index(gt.points);
  const eval_detail::NearestNeighborIndex map_index(map.points);
  const auto gt_to_map = map_index.nearest_all(gt.points);
  const auto map_to_gt = gt_index.nearest_all(map.points);

  // Raw counts per direction, [gt row][map column].
  std::vector<double> from_gt(kSize * kSize, 0.0), from_map(kSize * kSize, 0.0);
  std::vector<size_t> gt_class_points(kSize, 0), map_class_vertices(kSize, 0);
  size_t covered = 0, gt_entries = 0, map_entries = 0;
  const float max_d = static_cast<float>(options.max_distance_m);

  for (size_t i = 0; i < gt.size(); ++i) {
    const auto& hit = gt_to_map[i];
    if (hit.distance <= options.completeness_distance_m) ++covered;
    const int g = checked_label(gt.labels[i], "ground truth");
    if (g == 0) continue;  // unlabelled GT: ignored (ScanNet)
    ++result.gt_points_labelled;
    ++gt_class_points[g];
    int m = kNone;
    if (hit.distance <= max_d) m = map_labelled ? checked_label(map.labels[hit.index], "map") : 0;
    else ++result.gt_points_missed;
    from_gt[g * kSize + m] += 1.0;
    ++gt_entries;
  }

  std::vector<float> distances;
  distances.reserve(map.size());
  for (size_t i = 0; i < map.size(); ++i) {
    const auto& hit = map_to_gt[i];
    distances.push_back(hit.distance);
    const int m = map_labelled ? checked_label(map.labels[i], "map") : 0;
    if (m == 0) continue;  // an unlabelled vertex claims no class
    ++result.map_vertices_labelled;
    ++map_class_vertices[m];
    int g = kNone;
    if (hit.distance <= max_d) {
      g = gt.labels[hit.index];
      if (g == 0) continue;  // lands on ignored GT
    } else {
      ++result.map_vertices_off_surface;
      if (!options.unmatched_map_vertices_are_false_positives) continue;
    }
    from_map[g * kSize + m] += 1.0;
    ++map_entries;
  }

  // METHODS.md D: merge both directions, each normalised to weight 1/2.
  result.confusion.assign(kSize * kSize, 0.0);
  const double w_gt = gt_entries ? 0.5 / static_cast<double>(gt_entries) : 0.0;
  const double w_map = map_entries ? 0.5 / static_cast<double>(map_entries) : 0.0;
  for (int k = 0; k < kSize * kSize; ++k) result.confusion[k] = w_gt * from_gt[k] + w_map * from_map[k];

  double iou_sum = 0.0;
  for (int c = 1; c < kNumClasses; ++c) {
    double row = 0.0, col = 0.0;
    double gt_row = 0.0, map_col = 0.0;
    for (int k = 0; k < kSize; ++k) {
      row += result.confusion[c * kSize + k];
      gt_row += from_gt[c * kSize + k];
    }
    for (int r = 1; r < kSize; ++r) {
      col += result.confusion[r * kSize + c];
      map_col += from_map[r * kSize + c];
    }
    const double inter = result.confusion[c * kSize + c];
    const double uni = row + col - inter;
    if (uni <= 0.0) continue;
    ClassIoU cls;
    cls.class_id = static_cast<ClassId>(c);
    cls.intersection = inter;
    cls.uni = uni;
    cls.iou = inter / uni;
    cls.gt_points = gt_class_points[c];
    cls.map_vertices = map_class_vertices[c];
    cls.recall = gt_row > 0 ? from_gt[c * kSize + c] / gt_row : 0.0;
    cls.precision = map_col > 0 ? from_map[c * kSize + c] / map_col : 0.0;
    iou_sum += cls.iou;
    result.classes.push_back(cls);
  }
  result.miou = result.classes.empty() ? 0.0 : iou_sum / static_cast<double>(result.classes.size());

  if (!distances.empty()) {
    double sum = 0.0;
    for (float d : distances) sum += d;
    result.surface_error_mean_m = sum / static_cast<double>(distances.size());
    result.surface_error_median_m = median_of(std::move(distances));
  }
  result.completeness = static_cast<double>(covered) / static_cast<double>(gt.size());
  return result;
}

SemanticEvaluation evaluate_semantic_files(const std::filesystem::path& gt_ply,
                                           const std::filesystem::path& map_ply,
                                           const SemanticEvalOptions& options) {
  const TriangleMesh gt = read_ply(gt_ply);
  if (gt.vertices.empty()) throw Error(gt_ply, "no vertices");
  if (!gt.vertices.has_labels()) throw Error(gt_ply, "vertices carry no 'label' property");
  const TriangleMesh map = read_ply(map_ply);
  if (map.vertices.empty()) throw Error(map_ply, "no vertices");
  try {
    return evaluate_semantic(gt.vertices, map.vertices, options);
  } catch (const Error& e) {
    // Name the file the bad label came from.
    if (e.where() == "map") throw Error(map_ply, e.reason());
    if (e.where() == "ground truth") throw Error(gt_ply, e.reason());
    throw;
  }
}

nlohmann::json to_json(const SemanticEvaluation& e) {
  nlohmann::json classes = nlohmann::json::array();
  for (const auto& c : e.classes)
    classes.push_back({{"class", std::string(class_name(c.class_id))}, {"class_id", c.class_id},
                       {"iou", c.iou}, {"precision", c.precision}, {"recall", c.recall},
                       {"gt_points", c.gt_points}, {"map_vertices", c.map_vertices}});
  return {{"miou", e.miou},
          {"classes", classes},
          {"surface_error_mean_m", e.surface_error_mean_m},
          {"surface_error_median_m", e.surface_error_median_m},
          {"completeness", e.completeness},
          {"gt_points", e.gt_points},
          {"gt_points_labelled", e.gt_points_labelled},
          {"gt_points_missed", e.gt_points_missed},
          {"map_vertices", e.map_vertices},
          {"map_vertices_labelled", e.map_vertices_labelled},
          {"map_vertices_off_surface", e.map_vertices_off_surface},
          {"gt_points_non_finite", e.gt_points_non_finite},
          {"map_vertices_non_finite", e.map_vertices_non_finite}};
}

}  // namespace semap
