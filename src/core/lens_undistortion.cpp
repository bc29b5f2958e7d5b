#include "core/lens_undistortion.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace semap {

LensUndistortion::LensUndistortion(const CameraModel& camera) : registered_colour_(!camera.colour) {
  if (!camera.has_distortion()) return;
  const PinholeIntrinsics& k = camera.depth;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  std::array<double, 5> d = camera.distortion;
  const cv::Mat D(1, 5, CV_64F, d.data());
  // The same K for the output: the undistorted image keeps the intrinsics (and the image size).
  cv::initUndistortRectifyMap(K, D, cv::Mat(), K, cv::Size(k.width, k.height), CV_16SC2, map1_, map2_);
}

cv::Mat LensUndistortion::remap(const cv::Mat& image, int interpolation) const {
  if (image.empty() || image.size() != map1_.size()) return image;
  cv::Mat out;
  const int border = interpolation == cv::INTER_NEAREST ? cv::BORDER_CONSTANT : cv::BORDER_REPLICATE;
  cv::remap(image, out, map1_, map2_, interpolation, border, cv::Scalar::all(0));
  return out;
}

cv::Mat LensUndistortion::depth(const cv::Mat& depth) const {
  return active() ? remap(depth, cv::INTER_NEAREST) : depth;
}

void LensUndistortion::apply(Frame& frame) const {
  if (!active()) return;
  frame.depth = remap(frame.depth, cv::INTER_NEAREST);
  if (!registered_colour_) return;
  frame.rgb = remap(frame.rgb, cv::INTER_LINEAR);
  frame.labels = remap(frame.labels, cv::INTER_NEAREST);
  frame.instances = remap(frame.instances, cv::INTER_NEAREST);
}

CameraModel LensUndistortion::pinhole(CameraModel camera) {
  camera.distortion = {0, 0, 0, 0, 0};
  return camera;
}

}  // namespace semap
