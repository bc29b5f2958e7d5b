#pragma once
// Dense ground-truth points on every surface of the synthetic scene (gt_points.ply) and the
// visibility filter: a point is kept when at least one frame observed it, i.e. it projects
// into the image and that frame's clean rendered depth agrees within a tolerance (1.5 cm by
// default), so the evaluation's completeness only counts surfaces the camera has seen.
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/point_cloud.hpp"
#include "semap/core/pose.hpp"
#include "synth/scene.hpp"

namespace semap {

/// Points about `spacing` apart on all primitive and room surfaces, with outward normal, shaded
/// colour (as rendered), class label and instance id (0 = stuff). Hidden faces (e.g. undersides resting
/// on the floor) are included; the visibility filter removes them.
PointCloud sample_scene_surface(const SyntheticScene& scene, double spacing = 0.01);

/// Sets observed[i] = 1 for points seen in this frame: clean depth within `tolerance` and, when
/// the cloud has normals, the surface facing the camera.
void mark_observed_points(const PointCloud& cloud, const cv::Mat& depth_m, const Pose& T_world_camera,
                          const PinholeIntrinsics& intrinsics, double tolerance, std::vector<uint8_t>& observed);

/// The subset of `cloud` with observed[i] != 0.
PointCloud select_points(const PointCloud& cloud, const std::vector<uint8_t>& observed);

}  // namespace semap
