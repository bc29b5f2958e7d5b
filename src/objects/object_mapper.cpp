#include "objects/object_mapper.hpp"

#include <unordered_set>

#include <Eigen/Eigenvalues>
#include <chrono>
#include <tuple>
#include <algorithm>
#include <unordered_map>

#include <spdlog/spdlog.h>

namespace semap {

namespace {
double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

ObjectMapper::ObjectMapper(const ObjectsConfig& config, const CameraModel& camera)
    : config_(config), segmenter_(config, camera), map_(config), best_views_(camera.depth) {}

void ObjectMapper::process(const Frame& frame, const SegmentationResult& segmentation, const Pose& T_world_camera) {
  ++step_;
  const auto t0 = std::chrono::steady_clock::now();
  const auto segments = segmenter_.segment(frame, segmentation, T_world_camera);
  timings_.segmentation_ms += ms_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  map_.associate(segments, frame.index, step_);
  if (config_.enable_optimisation && step_ % static_cast<size_t>(config_.optimise_every) == 0) {
    optimisation_log_.push_back(map_.optimise(step_, false));
    ++timings_.optimisations;
  }
  timings_.association_ms += ms_since(t1);
  const auto t2 = std::chrono::steady_clock::now();
  best_views_.update(map_.instances(), frame, T_world_camera);
  timings_.best_views_ms += ms_since(t2);
  ++timings_.frames;
}

void ObjectMapper::accumulate(const Frame& frame, const SegmentationResult& segmentation, const Pose& T_world_camera) {
  if (!config_.accumulate_between_keyframes || map_.instances().empty()) return;
  const auto t0 = std::chrono::steady_clock::now();
  map_.extend(segmenter_.backproject(frame, segmentation, T_world_camera), frame.index);
  timings_.accumulation_ms += ms_since(t0);
  ++timings_.accumulated_frames;
}

void ObjectMapper::finish() {
  if (finished_) return;
  finished_ = true;
  if (config_.enable_optimisation && config_.final_optimisation && step_ % config_.optimise_every != 0) {
    optimisation_log_.push_back(map_.optimise(step_, true));
    ++timings_.optimisations;
    best_views_.forget_all_but(map_.instances());  // the views of objects this pass removed
  }
  const ObjectMapCounts c = counts();
  spdlog::debug("object map (C4, C5): {} instances created, {} folded at association, {} deleted ({} absorbed), "
               "{} merged -> {} objects", c.created, c.covered, c.deleted, c.absorbed, c.merged, c.final);
}

ObjectMapCounts ObjectMapper::counts() const {
  ObjectMapCounts c;
  c.created = map_.created();
  for (const OptimisationStats& s : optimisation_log_) {
    c.deleted += static_cast<size_t>(s.deleted);
    c.absorbed += static_cast<size_t>(s.absorbed);
    c.merged += static_cast<size_t>(s.merged);
  }
  c.final = map_.instances().size();
  c.covered = c.created - c.deleted - c.merged - c.final;
  return c;
}

OrientedBox fit_oriented_box(const std::vector<Eigen::Vector3f>& points, double trim_fraction) {
  OrientedBox box;
  if (points.empty()) return box;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p.cast<double>();
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector3d d = p.cast<double>() - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  Eigen::Matrix3d axes = solver.eigenvectors();
  if (axes.determinant() < 0) axes.col(0) = -axes.col(0);
  Eigen::Vector3d lo, hi;
  std::vector<double> coordinate(points.size());
  for (int a = 0; a < 3; ++a) {
    for (size_t i = 0; i < points.size(); ++i) coordinate[i] = axes.col(a).dot(points[i].cast<double>() - mean);
    std::tie(lo[a], hi[a]) = trimmed_range(coordinate, trim_fraction);
  }
  box.rotation = axes.cast<float>();
  box.extent = (hi - lo).cast<float>();
  box.center = (mean + axes * (0.5 * (lo + hi))).cast<float>();
  return box;
}

namespace {

/// The instance's exported points: projected onto the surface when asked, one per map voxel.
void exported_points(const ObjectMap& map, const ObjectInstance& inst, const ObjectMapper::SurfaceProjection& onto_surface,
                     bool drop_other_classes, ObjectSummary& o) {
  if (!onto_surface) {
    o.points = inst.points;
    o.colours = inst.colours;
    return;
  }
  const ObjectMapper::SurfaceSamples surface = onto_surface(inst.points);
  const std::vector<bool> other = drop_other_classes ? points_of_other_classes(surface.labels, inst.class_id())
                                                     : std::vector<bool>(surface.points.size(), false);
  std::unordered_set<uint64_t> seen;
  for (size_t i = 0; i < surface.points.size(); ++i)
    if (!other[i] && seen.insert(map.voxel_key(surface.points[i])).second) {
      o.points.push_back(surface.points[i]);
      o.colours.push_back(inst.colours[i]);
    }
}

}  // namespace

std::vector<bool> points_of_other_classes(const std::vector<ClassId>& labels, ClassId class_id) {
  std::vector<bool> other(labels.size(), false);
  size_t n_other = 0;
  for (size_t i = 0; i < labels.size(); ++i)
    if (labels[i] != 0 && labels[i] != class_id) other[i] = true, ++n_other;
  if (2 * n_other > labels.size()) std::fill(other.begin(), other.end(), false);
  return other;
}

std::vector<ObjectSummary> ObjectMapper::summaries(const SurfaceProjection& onto_surface) const {
  std::vector<ObjectSummary> out;
  for (const auto& inst : map_.instances()) {
    if (inst.points.empty()) continue;
    ObjectSummary o;
    o.id = inst.id;
    o.class_id = inst.class_id();
    // Share of each class in the evidence over frames (C3); the detector's own uncertainty (the
    // "other" residual of C5's augmented vector) is the confidence, not a class.
    const std::vector<double> shares = evidence_shares(inst.score_sum);
    for (size_t k = 0; k < shares.size(); ++k)
      if (shares[k] >= 0.005) o.class_distribution[std::string(class_name(static_cast<ClassId>(k)))] = shares[k];
    o.confidence = 1.0 - inst.mean_scores()[0];
    o.best_view_jpeg = best_views_.jpeg(inst.id);
    exported_points(map_, inst, config_.points_on_surface ? onto_surface : SurfaceProjection{},
                    config_.drop_points_of_other_classes, o);
    // Boxes describe the object's body: its largest cluster, trimmed of stray points.
    const std::vector<Eigen::Vector3f> body = largest_cluster(o.points, config_.box_cluster_distance);
    const Eigen::AlignedBox3f aabb = trimmed_box(body, config_.box_trim_fraction);
    o.aabb_min = aabb.min();
    o.aabb_max = aabb.max();
    o.box = fit_oriented_box(body, config_.box_trim_fraction);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& p : o.points) sum += p.cast<double>();
    o.centroid = (sum / static_cast<double>(o.points.size())).cast<float>();
    o.merge_count = inst.n;
    o.associations = inst.total_associations;
    o.first_frame = inst.first_frame;
    o.last_frame = inst.last_frame;
    o.state = state_name(inst.state);
    out.push_back(std::move(o));
  }
  return out;
}

nlohmann::json ObjectMapper::to_json() const { return objects_json(summaries()); }

}  // namespace semap
