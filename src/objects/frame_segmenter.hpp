#pragma once
// Per-keyframe object segments (METHODS.md C2): mask-guided supervoxel clustering, or plain
// mask back-projection for comparison.
#include <Eigen/Core>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"
#include "semap/core/labels.hpp"
#include "semap/objects/objects_config.hpp"
#include "semap/segmentation/segmenter.hpp"

namespace semap {

/// One object segment of a frame: the points of one detection, in world coordinates.
struct ObjectSegment {
  std::vector<Eigen::Vector3f> points;  ///< world frame, metres
  std::vector<Rgb8> colours;            ///< same size as points
  ClassId class_id = 0;
  float score = 0.f;
  std::vector<double> class_scores;     ///< size kNumClasses (one-hot * score when the detector gives none)
  int detection = -1;                   ///< index into SegmentationResult::instances
};

struct FrameSegmentationStats {
  size_t cloud_points = 0;
  size_t supervoxels = 0;
  size_t planes = 0;
  size_t quasi_segments = 0;
};

class FrameSegmenter {
 public:
  FrameSegmenter(const ObjectsConfig& config, const CameraModel& camera);
  /// Object segments of one frame (C2). Throws semap::Error on inconsistent images.
  std::vector<ObjectSegment> segment(const Frame& frame, const SegmentationResult& seg, const Pose& T_world_camera,
                                     FrameSegmentationStats* stats = nullptr) const;
  /// Plain mask back-projection whatever segmentation_mode says (ObjectMapper::accumulate).
  std::vector<ObjectSegment> backproject(const Frame& frame, const SegmentationResult& seg,
                                         const Pose& T_world_camera) const;

 private:
  std::vector<ObjectSegment> run(const Frame& frame, const SegmentationResult& seg, const Pose& T_world_camera,
                                 bool backprojection, FrameSegmentationStats* stats) const;
  ObjectsConfig config_;
  CameraModel camera_;
};

/// Score vector of a detection: its class_scores when complete, else one-hot(class) * score.
std::vector<double> detection_score_vector(const InstanceDetection& det);

}  // namespace semap
