#pragma once
// The fused surface seen from a camera (METHODS.md A2: "the paper registers the frame's point
// cloud to the model's projected point cloud"; KinectFusion's model prediction): the TSDF's zero
// level along each pixel ray, searched near a measured depth so that a keyframe's own depth
// guides the search (one short secant search per pixel instead of a full ray march).
#include <opencv2/core.hpp>

#include "semap/core/camera.hpp"
#include "semap/core/pose.hpp"
#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

/// For each pixel of `depth_m` (CV_32FC1, metres; <= 0 or NaN = invalid) with a valid depth:
/// the depth of the TSDF's zero crossing along the pixel's ray within the truncation distance
/// of the measured depth (secant steps on the trilinear sdf). Pixels without such a crossing
/// (unobserved voxels, no surface there) are 0. `intrinsics` describe `depth_m`'s pixels,
/// `T_world_camera` the camera in the map's frame. Reads the map only: any thread, while no
/// thread changes the map. Row-parallel (TBB).
cv::Mat surface_depth_along_rays(const TsdfMap& map, const cv::Mat& depth_m, const PinholeIntrinsics& intrinsics,
                                 const Pose& T_world_camera);

}  // namespace semap
