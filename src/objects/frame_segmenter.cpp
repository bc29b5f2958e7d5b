#include "objects/frame_segmenter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "semap/core/error.hpp"
#include "core/statistics.hpp"
#include "objects/segment_graph.hpp"
#include "objects/supervoxel_graph.hpp"

namespace semap {

std::vector<double> detection_score_vector(const InstanceDetection& det) {
  std::vector<double> scores(kNumClasses, 0.0);
  if (static_cast<int>(det.class_scores.size()) == kNumClasses) {
    for (int k = 0; k < kNumClasses; ++k) scores[k] = std::max(0.f, det.class_scores[k]);
  } else if (det.class_id < kNumClasses) {
    scores[det.class_id] = det.score > 0.f ? det.score : 1.0;
  }
  return scores;
}

FrameSegmenter::FrameSegmenter(const ObjectsConfig& config, const CameraModel& camera)
    : config_(config), camera_(camera) {
  config_.validate();
}

namespace {

struct FrameCloud {
  std::vector<Eigen::Vector3f> points;  // camera frame
  std::vector<Rgb8> colours;
  std::vector<int> mask;                // 1-based detection index, 0 = background
};

// Per-pixel detection index (1-based) at depth resolution; the higher score wins overlaps.
std::vector<int> mask_index_image(const SegmentationResult& seg, int width, int height, double min_score) {
  std::vector<int> index(static_cast<size_t>(width) * height, 0);
  std::vector<int> order(seg.instances.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return seg.instances[a].score < seg.instances[b].score; });
  for (int d : order) {
    const auto& det = seg.instances[d];
    if (det.mask.empty() || det.score < min_score || det.class_id == 0 || is_stuff(det.class_id)) continue;
    if (det.mask.type() != CV_8UC1) throw Error("segmentation", "instance mask must be CV_8UC1");
    const int mw = det.mask.cols, mh = det.mask.rows;
    for (int v = 0; v < height; ++v) {
      const uint8_t* row = det.mask.ptr<uint8_t>(mh == height ? v : v * mh / height);
      for (int u = 0; u < width; ++u)
        if (row[mw == width ? u : u * mw / width]) index[static_cast<size_t>(v) * width + u] = d + 1;
    }
  }
  return index;
}

// Robust depth gate per mask: a detector's mask bleeds past the object's silhouette onto the
// surface behind it (the counter or wall seen past a table's edge, the floor between chair
// legs). Such pixels lie far from the bulk of the mask in depth; they become background so
// neither C2 nor the dense pass gives them to the object. Gate: |z - median| <= max(k * 1.4826 *
// MAD, min_band * median), statistics from every `stride`-th pixel of the mask.
void gate_mask_depth(std::vector<int>& mask_index, const cv::Mat& depth, int num_detections, int stride, double k,
                     double min_band, double max_depth) {
  if (k <= 0.0 || num_detections == 0) return;
  const int width = depth.cols, height = depth.rows;
  std::vector<std::vector<float>> samples(static_cast<size_t>(num_detections) + 1);
  for (int v = 0; v < height; v += stride) {
    const float* drow = depth.ptr<float>(v);
    for (int u = 0; u < width; u += stride) {
      const int m = mask_index[static_cast<size_t>(v) * width + u];
      if (m != 0 && drow[u] > 0.f && drow[u] <= max_depth) samples[m].push_back(drow[u]);
    }
  }
  std::vector<float> lo(samples.size(), 0.f), hi(samples.size(), std::numeric_limits<float>::infinity());
  for (size_t m = 1; m < samples.size(); ++m) {
    if (samples[m].empty()) continue;
    const double median = median_of(samples[m]);
    std::vector<float> deviation;
    deviation.reserve(samples[m].size());
    for (float z : samples[m]) deviation.push_back(std::abs(z - static_cast<float>(median)));
    const double band = std::max(k * 1.4826 * median_of(std::move(deviation)), min_band * median);
    lo[m] = static_cast<float>(median - band);
    hi[m] = static_cast<float>(median + band);
  }
  for (int v = 0; v < height; ++v) {
    const float* drow = depth.ptr<float>(v);
    for (int u = 0; u < width; ++u) {
      int& m = mask_index[static_cast<size_t>(v) * width + u];
      if (m != 0 && drow[u] > 0.f && (drow[u] < lo[m] || drow[u] > hi[m])) m = 0;
    }
  }
}

}  // namespace

std::vector<ObjectSegment> FrameSegmenter::segment(const Frame& frame, const SegmentationResult& seg,
                                                   const Pose& T_world_camera, FrameSegmentationStats* stats) const {
  return run(frame, seg, T_world_camera, config_.segmentation_mode == SegmentationMode::backprojection, stats);
}

std::vector<ObjectSegment> FrameSegmenter::backproject(const Frame& frame, const SegmentationResult& seg,
                                                       const Pose& T_world_camera) const {
  return run(frame, seg, T_world_camera, true, nullptr);
}

std::vector<ObjectSegment> FrameSegmenter::run(const Frame& frame, const SegmentationResult& seg,
                                               const Pose& T_world_camera, bool backprojection,
                                               FrameSegmentationStats* stats) const {
  std::vector<ObjectSegment> result;
  if (frame.depth.empty()) return result;
  if (frame.depth.type() != CV_32FC1) throw Error(frame.depth_path, "depth must be CV_32FC1 metres");
  const int width = frame.depth.cols, height = frame.depth.rows;
  const auto& intr = camera_.depth;
  const double sx = static_cast<double>(intr.width) / width, sy = static_cast<double>(intr.height) / height;
  std::vector<int> mask_index = mask_index_image(seg, width, height, config_.mask_min_score);
  gate_mask_depth(mask_index, frame.depth, static_cast<int>(seg.instances.size()), config_.pixel_stride,
                  config_.mask_depth_gate_k, config_.mask_depth_gate_min, config_.max_depth);
  if (std::none_of(mask_index.begin(), mask_index.end(), [](int m) { return m != 0; })) return result;

  const bool has_rgb = !frame.rgb.empty() && frame.rgb.type() == CV_8UC3;
  auto colour_at = [&](int u, int v) {
    if (!has_rgb) return Rgb8{};
    const auto& bgr = frame.rgb.at<cv::Vec3b>(v * frame.rgb.rows / height, u * frame.rgb.cols / width);
    return Rgb8{bgr[2], bgr[1], bgr[0]};
  };
  FrameCloud cloud;
  const int stride = config_.pixel_stride;
  // Cloud point index of each stride cell's sample (-1: none), for the dense point pass below.
  const int cells_u = (width + stride - 1) / stride;
  std::vector<int> cell_point(static_cast<size_t>(cells_u) * ((height + stride - 1) / stride), -1);
  for (int v = 0; v < height; v += stride) {
    const float* drow = frame.depth.ptr<float>(v);
    for (int u = 0; u < width; u += stride) {
      const float z = drow[u];
      if (!(z > 0.f) || z > config_.max_depth) continue;
      const int m = mask_index[static_cast<size_t>(v) * width + u];
      if (backprojection && m == 0) continue;
      cell_point[static_cast<size_t>(v / stride) * cells_u + u / stride] = static_cast<int>(cloud.points.size());
      cloud.points.push_back(intr.backproject(u * sx, v * sy, z).cast<float>());
      cloud.colours.push_back(colour_at(u, v));
      cloud.mask.push_back(m);
    }
  }
  if (stats) stats->cloud_points = cloud.points.size();

  // Which points make the segment of each detection (1-based index -> point indices).
  std::map<int, std::vector<int>> points_of_detection;
  if (backprojection) {
    for (size_t i = 0; i < cloud.points.size(); ++i) points_of_detection[cloud.mask[i]].push_back(static_cast<int>(i));
  } else {
    SupervoxelParams sv;
    sv.voxel_resolution = static_cast<float>(config_.voxel_resolution);
    sv.seed_resolution = static_cast<float>(config_.seed_resolution);
    sv.colour_importance = static_cast<float>(config_.colour_importance);
    sv.spatial_importance = static_cast<float>(config_.spatial_importance);
    sv.normal_importance = static_cast<float>(config_.normal_importance);
    sv.adopt_radius = static_cast<float>(config_.supervoxel_adopt_radius);
    SupervoxelGraph graph = build_supervoxel_graph(cloud.points, cloud.colours, sv);
    const int num_masks = static_cast<int>(seg.instances.size()) + 1;
    for (auto& node : graph.nodes) {
      // m_i (C2.3): the mask covering most of the supervoxel's points.
      std::vector<int> votes(num_masks, 0);
      for (int p : node.point_indices) ++votes[cloud.mask[p]];
      node.mask = static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
      // C2.6: the mask at the centre's pixel (the majority when the centre falls outside).
      node.centre_mask = node.mask;
      if (node.centroid.z() > 0.f) {
        const Eigen::Vector2d px = intr.project(node.centroid.cast<double>());
        const int u = static_cast<int>(std::lround(px.x() / sx)), v = static_cast<int>(std::lround(px.y() / sy));
        if (u >= 0 && v >= 0 && u < width && v < height) node.centre_mask = mask_index[static_cast<size_t>(v) * width + u];
      }
    }
    SupportPlaneParams plane_params;
    plane_params.max_curvature = static_cast<float>(config_.plane_max_curvature);
    plane_params.max_angle_deg = static_cast<float>(config_.plane_max_angle_deg);
    plane_params.max_distance = static_cast<float>(config_.plane_max_distance);
    plane_params.min_supervoxels = config_.plane_min_supervoxels;
    plane_params.min_extent = static_cast<float>(config_.plane_min_extent);
    const std::vector<int> planes = assign_support_planes(graph, plane_params);
    for (size_t i = 0; i < graph.nodes.size(); ++i) graph.nodes[i].plane = planes[i];
    const std::vector<bool> convex = truly_convex_edges(graph, static_cast<float>(config_.convex_sanity_angle_deg));
    std::vector<WeightedEdge> edges;
    edges.reserve(graph.edges.size());
    for (size_t e = 0; e < graph.edges.size(); ++e) {
      const auto [a, b] = graph.edges[e];
      const auto& na = graph.nodes[a];
      const auto& nb = graph.nodes[b];
      // C2.2: omega = omega_sem + omega_geo.
      const float w = semantic_weight(na.mask, nb.mask, static_cast<float>(config_.weight_different_masks),
                                      static_cast<float>(config_.weight_background)) +
                      geometric_weight(na.plane, nb.plane, na.normal, nb.normal, convex[e]);
      edges.push_back({a, b, w});
    }
    const std::vector<int> component =
        felzenszwalb_cluster(static_cast<int>(graph.nodes.size()), edges, static_cast<float>(config_.felzenszwalb_k));
    const int num_components = component.empty() ? 0 : *std::max_element(component.begin(), component.end()) + 1;
    // C2.6: each quasi-object segment takes the majority centre label of its supervoxels.
    std::vector<std::vector<int>> votes(num_components, std::vector<int>(num_masks, 0));
    for (size_t i = 0; i < graph.nodes.size(); ++i) ++votes[component[i]][graph.nodes[i].centre_mask];
    std::vector<int> component_label(num_components, 0);
    for (int c = 0; c < num_components; ++c)
      component_label[c] = static_cast<int>(std::max_element(votes[c].begin(), votes[c].end()) - votes[c].begin());
    for (size_t i = 0; i < graph.nodes.size(); ++i) {
      const int label = component_label[component[i]];
      const auto& node = graph.nodes[i];
      if (!config_.point_mask_refinement || label == 0) {
        auto& list = points_of_detection[label];
        list.insert(list.end(), node.point_indices.begin(), node.point_indices.end());
        continue;
      }
      // Extension to C2.6 (config point_mask_refinement): the segment is C2's, but a point
      // joins it only where its own pixel carries this detection's mask. Supervoxels straddle
      // borders, so without this the floor under a chair or the table under a monitor joins
      // the object. Measured with the unowned rule below: D10n GT masks, 60 keyframes, WOv
      // 0.790 -> 0.816; noisy test supervoxel WOv 0.747 -> 0.777. Also keeping background-mask
      // points of supervoxels mostly of this mask (eroded borders) scored lower on both
      // (0.809, 0.762).
      for (int p : node.point_indices) points_of_detection[cloud.mask[p] == label ? label : 0].push_back(p);
    }
    if (config_.point_mask_refinement) {
      // Points VCCS leaves in no supervoxel (beyond supervoxel_adopt_radius of any) carry no C2
      // evidence: their own mask decides, as in back-projection, instead of dropping them.
      std::vector<char> owned(cloud.points.size(), 0);
      for (const auto& node : graph.nodes)
        for (int p : node.point_indices) owned[p] = 1;
      for (size_t p = 0; p < cloud.points.size(); ++p)
        if (!owned[p]) points_of_detection[cloud.mask[p]].push_back(static_cast<int>(p));
    }
    if (stats) {
      stats->supervoxels = graph.nodes.size();
      stats->planes = planes.empty() ? 0 : static_cast<size_t>(*std::max_element(planes.begin(), planes.end()));
      stats->quasi_segments = static_cast<size_t>(num_components);
    }
  }

  // Dense points (config point_stride < pixel_stride): every point_stride-th pixel joins the
  // segment of its stride cell's sample when its depth agrees (same surface) and its own mask is
  // the segment's detection, so the object keeps
  // the surface of every observation at the map's resolution while C2 runs on the coarser cloud.
  const int fine = std::min(config_.point_stride, stride);
  struct ExtraPoints {
    std::vector<Eigen::Vector3f> points;
    std::vector<Rgb8> colours;
  };
  std::map<int, ExtraPoints> extra_of_detection;
  if (fine < stride) {
    std::vector<int> label_of_point(cloud.points.size(), 0);
    for (const auto& [label, indices] : points_of_detection)
      for (int i : indices) label_of_point[i] = label;
    for (int v = 0; v < height; v += fine) {
      const float* drow = frame.depth.ptr<float>(v);
      for (int u = 0; u < width; u += fine) {
        if (u % stride == 0 && v % stride == 0) continue;  // the sample itself
        const float z = drow[u];
        if (!(z > 0.f) || z > config_.max_depth) continue;
        const int sample = cell_point[static_cast<size_t>(v / stride) * cells_u + u / stride];
        if (sample < 0 || label_of_point[sample] == 0) continue;
        const float z_sample = cloud.points[sample].z();
        if (std::abs(z - z_sample) > config_.dense_depth_tolerance * std::max(1.f, z_sample)) continue;
        // Only where the pixel's own mask confirms the segment: C2 decides at the coarse samples.
        if (mask_index[static_cast<size_t>(v) * width + u] != label_of_point[sample]) continue;
        auto& extra = extra_of_detection[label_of_point[sample]];
        extra.points.push_back(intr.backproject(u * sx, v * sy, z).cast<float>());
        extra.colours.push_back(colour_at(u, v));
      }
    }
  }

  const Eigen::Isometry3f T = T_world_camera.cast<float>();
  for (const auto& [label, indices] : points_of_detection) {
    if (label == 0 || static_cast<int>(indices.size()) < config_.min_segment_points) continue;
    const auto& det = seg.instances[label - 1];
    ObjectSegment segment;
    segment.class_id = det.class_id;
    segment.score = det.score;
    segment.class_scores = detection_score_vector(det);
    segment.detection = label - 1;
    const auto extra_it = extra_of_detection.find(label);
    const size_t extra_count = extra_it == extra_of_detection.end() ? 0 : extra_it->second.points.size();
    segment.points.reserve(indices.size() + extra_count);
    segment.colours.reserve(indices.size() + extra_count);
    for (int i : indices) {
      segment.points.push_back(T * cloud.points[i]);
      segment.colours.push_back(cloud.colours[i]);
    }
    if (extra_count > 0) {
      for (const auto& p : extra_it->second.points) segment.points.push_back(T * p);
      segment.colours.insert(segment.colours.end(), extra_it->second.colours.begin(), extra_it->second.colours.end());
    }
    result.push_back(std::move(segment));
  }
  return result;
}

}  // namespace semap
