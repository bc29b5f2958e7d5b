#pragma once
// Colour <-> depth registration (METHODS.md B2): images computed on the colour camera
// (labels, masks, colour) resampled at depth-camera pixels.
#include <opencv2/core.hpp>

#include "semap/core/camera.hpp"
#include "semap/segmentation/segmenter.hpp"

namespace semap {

/// True when the camera has a separate colour camera whose intrinsics or extrinsic differ
/// from the depth camera (otherwise colour and depth pixels coincide).
bool needs_registration(const CameraModel& camera);

/// For each depth pixel with depth z > 0: back-project with the depth intrinsics, move into the
/// colour camera (P_c = T_depth_colour^-1 P_d), project with the colour intrinsics. Returns
/// CV_32FC2 colour-pixel coordinates (x, y) per depth pixel; (-1, -1) where depth is invalid,
/// the point is behind the colour camera or projects outside the colour image.
cv::Mat colour_lookup_map(const cv::Mat& depth_m, const CameraModel& camera);

/// Samples `colour_image` (any type, colour-camera resolution) at the map's coordinates:
/// nearest for labels/ids (INTER_NEAREST), bilinear for colour. Unmapped pixels get 0.
cv::Mat register_image(const cv::Mat& colour_image, const cv::Mat& lookup_map, int interpolation);

/// Registers everything in `result` (labels, instance ids, confidence, probabilities, masks;
/// boxes recomputed from the registered masks; instances left without pixels are dropped).
SegmentationResult register_result(const SegmentationResult& result, const cv::Mat& lookup_map);

}  // namespace semap
