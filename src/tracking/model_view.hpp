#pragma once
// What tracking may read of the fused model (issue 42, METHODS.md A2: "the paper registers the
// frame's point cloud to the model's projected point cloud"). The pipeline owns the map and
// hands the tracker this narrow, read-only view; tracking never reads the map's internals.
#include <opencv2/core.hpp>

#include "semap/core/camera.hpp"
#include "semap/core/pose.hpp"

namespace semap {

class ModelView {
 public:
  virtual ~ModelView() = default;
  /// The model's surface depth along each valid pixel ray of `depth_m` (CV_32FC1, metres, the
  /// camera `intrinsics` at `T_world_camera`), found near the measured depth; 0 where the model
  /// has no surface there (not yet observed). Thread safety: the implementation serialises with
  /// the map's writers; callable from the tracking thread at any time.
  virtual cv::Mat surface_depth(const cv::Mat& depth_m, const PinholeIntrinsics& intrinsics,
                                const Pose& T_world_camera) const = 0;
};

}  // namespace semap
