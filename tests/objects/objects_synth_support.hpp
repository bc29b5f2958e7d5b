#pragma once
// Shared by the object-map tests on the synthetic world: ground-truth segmentation results,
// running the mapper over a dataset, per-class counts and WOv (METHODS.md C6, the library's
// evaluation).
#include <filesystem>
#include <map>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include <opencv2/imgproc.hpp>

#include "semap/core/labels.hpp"
#include "semap/eval/object_metrics.hpp"
#include "semap/io/dataset.hpp"
#include "semap/io/ply_io.hpp"
#include "objects/object_mapper.hpp"
#include "semap/pipeline/outputs.hpp"
#include "semap/synth/segmentation_noise.hpp"
#include "synth/synth_config.hpp"

namespace semap::test {

/// One instance per ground-truth instance id, class = majority label, one-hot class scores.
inline SegmentationResult segmentation_from_labels(const cv::Mat& labels, const cv::Mat& instances,
                                                   int false_positives_min_px = 0) {
  SegmentationResult seg;
  std::map<uint16_t, std::map<ClassId, int>> votes;
  for (int v = 0; v < instances.rows; ++v)
    for (int u = 0; u < instances.cols; ++u) {
      const uint16_t inst = instances.at<uint16_t>(v, u);
      if (inst) ++votes[inst][labels.at<uint8_t>(v, u)];
    }
  uint16_t next = 1;
  for (const auto& [inst, classes] : votes) {
    ClassId best = 0;
    int best_votes = -1;
    for (const auto& [c, n] : classes)
      if (n > best_votes && c != 0) best = c, best_votes = n;
    if (best == 0) continue;
    InstanceDetection det;
    det.id = next++;
    det.class_id = best;
    det.score = 1.f;
    det.class_scores.assign(kNumClasses, 0.f);
    det.class_scores[best] = 1.f;
    cv::compare(instances, inst, det.mask, cv::CMP_EQ);
    det.box = cv::boundingRect(det.mask);
    seg.instances.push_back(std::move(det));
  }
  if (false_positives_min_px > 0) {
    // Noisy mode: object-class pixels without an instance (flickered stuff regions) become
    // false-positive detections, one per connected component.
    for (int c = 1; c < kNumClasses; ++c) {
      if (is_stuff(static_cast<ClassId>(c))) continue;
      cv::Mat region = (labels == c) & (instances == 0);
      if (cv::countNonZero(region) < false_positives_min_px) continue;
      cv::Mat components;
      const int n = cv::connectedComponents(region, components, 8, CV_32S);
      for (int k = 1; k < n; ++k) {
        InstanceDetection det;
        det.mask = components == k;
        if (cv::countNonZero(det.mask) < false_positives_min_px) continue;
        det.id = next++;
        det.class_id = static_cast<ClassId>(c);
        det.score = 1.f;
        det.class_scores.assign(kNumClasses, 0.f);
        det.class_scores[c] = 1.f;
        det.box = cv::boundingRect(det.mask);
        seg.instances.push_back(std::move(det));
      }
    }
  }
  return seg;
}

struct MapRunResult {
  nlohmann::json objects;  // objects.json
  std::vector<ObjectInstance> instances;
  ObjectMapperTimings timings;
};

/// Runs the object mapper over every `frame_step`-th frame with ground-truth poses; with
/// `noise`, segmentation comes from apply_segmentation_noise (seed = frame index). The frames
/// between go to ObjectMapper::accumulate (as the pipeline does when every frame is labelled)
/// when config.accumulate_between_keyframes.
inline MapRunResult run_object_mapper(const std::filesystem::path& dataset, const ObjectsConfig& config,
                                      const std::optional<SegmentationNoiseParams>& noise, int frame_step,
                                      const std::filesystem::path& write_to = {}) {
  const auto reader = open_dataset(dataset);
  ObjectMapper mapper(config, reader->camera());
  const size_t step = config.accumulate_between_keyframes ? 1 : static_cast<size_t>(frame_step);
  for (size_t i = 0; i < reader->size(); i += step) {
    const Frame frame = reader->load(i);
    SegmentationResult seg;
    if (noise) {
      const auto [labels, instances] = apply_segmentation_noise(frame.labels, frame.instances, i, *noise);
      seg = segmentation_from_labels(labels, instances, 100);
    } else {
      seg = segmentation_from_labels(frame.labels, frame.instances);
    }
    if (i % frame_step == 0) mapper.process(frame, seg, *frame.gt_T_world_camera);
    else mapper.accumulate(frame, seg, *frame.gt_T_world_camera);
  }
  mapper.finish();
  if (!write_to.empty()) write_objects(mapper.summaries(), write_to);
  return {mapper.to_json(), mapper.instances(), mapper.timings()};
}

struct GtObjects {
  std::map<uint32_t, std::vector<Eigen::Vector3f>> points;  // instance -> observed surface points
  std::map<uint32_t, ClassId> classes;
};

/// Ground-truth objects from gt_points.ply (objects with at least min_points observed points).
inline GtObjects load_gt_objects(const std::filesystem::path& dataset, size_t min_points = 50) {
  const TriangleMesh mesh = read_ply(dataset / "gt_points.ply");
  GtObjects gt;
  std::map<uint32_t, std::map<ClassId, int>> votes;
  const auto& cloud = mesh.vertices;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const uint32_t inst = cloud.has_instances() ? cloud.instances[i] : 0;
    if (!inst) continue;
    gt.points[inst].push_back(cloud.points[i]);
    ++votes[inst][cloud.has_labels() ? cloud.labels[i] : 0];
  }
  for (auto it = gt.points.begin(); it != gt.points.end();) {
    if (it->second.size() < min_points) {
      it = gt.points.erase(it);
      continue;
    }
    ClassId best = 0;
    int n = -1;
    for (const auto& [c, k] : votes[it->first])
      if (k > n) best = c, n = k;
    gt.classes[it->first] = best;
    ++it;
  }
  return gt;
}

/// WOv (METHODS.md C6) of the predicted instances by the library's object evaluation
/// (semap/eval/object_metrics.hpp: surface IoU within `distance_m`, weights on a grid of the
/// same size). SEMAP_OBJECTS_DEBUG prints every GT object's best match.
inline double weighted_overlap(const GtObjects& gt, const std::vector<ObjectInstance>& predicted,
                               double distance_m = 0.03) {
  std::vector<EvalObject> truth, map;
  for (const auto& [inst, pts] : gt.points) truth.push_back({inst, gt.classes.at(inst), pts});
  for (size_t k = 0; k < predicted.size(); ++k)
    map.push_back({static_cast<uint32_t>(k), predicted[k].class_id(), predicted[k].points});
  ObjectEvalOptions options;
  options.match_distance_m = options.voxel_size_m = distance_m;
  const ObjectEvaluation e = evaluate_objects(truth, map, options);
  if (std::getenv("SEMAP_OBJECTS_DEBUG"))
    for (const auto& g : e.per_gt)
      std::cout << "gt " << g.gt_id << " " << class_name(g.class_id) << " voxels " << g.voxels << " IoU "
                << g.best_iou << " precision " << g.best_precision << " recall " << g.best_recall << "\n";
  return e.wov;
}

inline std::map<std::string, int> counts_per_class(const std::vector<ObjectInstance>& instances) {
  std::map<std::string, int> counts;
  for (const auto& inst : instances) ++counts[std::string(class_name(inst.class_id()))];
  return counts;
}
inline std::map<std::string, int> counts_per_class(const GtObjects& gt) {
  std::map<std::string, int> counts;
  for (const auto& [inst, cls] : gt.classes) ++counts[std::string(class_name(cls))];
  return counts;
}

}  // namespace semap::test
