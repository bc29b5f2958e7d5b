#pragma once
// Lens undistortion of RGB-D frames (issue 16: TUM fr1/fr2 have strong radial distortion,
// k1 = 0.26; the pinhole model misplaces corner pixels by up to ~30 px, which biases the
// tracked rotation by ~4 % and warps the map). Frames are undistorted once, where they enter
// (dataset readers, Mapper::add_frame), so tracking, segmentation, the TSDF and the object map
// all work in the ideal pinhole image of the same intrinsics.
#include <opencv2/core.hpp>

#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"

namespace semap {

class LensUndistortion {
 public:
  /// Maps for `camera.distortion` on the depth image (= the registered colour image); none
  /// when the camera has no distortion. Thread safety: apply() is const and may run concurrently.
  explicit LensUndistortion(const CameraModel& camera);
  bool active() const { return !map1_.empty(); }
  /// Depth, labels and instances by nearest neighbour (no mixing across edges), colour
  /// bilinear when it is registered to depth (a separate colour camera is left as it is).
  void apply(Frame& frame) const;
  /// Depth only (CV_32FC1), nearest neighbour.
  cv::Mat depth(const cv::Mat& depth) const;
  /// The camera of the undistorted images: the same one without distortion.
  static CameraModel pinhole(CameraModel camera);

 private:
  cv::Mat remap(const cv::Mat& image, int interpolation) const;
  bool registered_colour_ = true;
  cv::Mat map1_, map2_;
};

}  // namespace semap
