#pragma once
// OpenCV's RGB-D odometry (opencv_contrib rgbd: cv::rgbd::RgbdICPOdometry, photometric +
// point-to-plane ICP, frame to frame): the second comparison baseline of issue 16 beside
// Open3D. Only available when the build found opencv_rgbd (SEMAP_HAVE_OPENCV_RGBD).
#ifdef SEMAP_HAVE_OPENCV_RGBD
#include <chrono>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"
#include "semap/core/pose.hpp"

namespace semap::baseline {

struct OpencvOdometryRun {
  Trajectory trajectory;         ///< one pose per frame (a failed step keeps the last pose)
  std::vector<double> frame_ms;  ///< wall time per frame
  size_t failures = 0;
};

/// Chains cv::rgbd::RgbdICPOdometry (OpenCV defaults: 4 pyramid levels, depth in [0, 4] m,
/// last motion as initial guess) over the frames.
inline OpencvOdometryRun run_opencv_odometry(const std::vector<Frame>& frames, const CameraModel& camera) {
  const auto& k = camera.depth;
  const cv::Mat K = (cv::Mat_<float>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  cv::Ptr<cv::rgbd::RgbdICPOdometry> odometry = cv::rgbd::RgbdICPOdometry::create(K, 0.0f, 4.0f);
  OpencvOdometryRun run;
  Pose pose = Pose::Identity();
  cv::Mat last_motion = cv::Mat::eye(4, 4, CV_64FC1);
  cv::Ptr<cv::rgbd::OdometryFrame> previous;
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    cv::Mat gray;
    cv::cvtColor(frames[i].rgb, gray, cv::COLOR_BGR2GRAY);
    if (gray.size() != frames[i].depth.size()) cv::resize(gray, gray, frames[i].depth.size());
    cv::Ptr<cv::rgbd::OdometryFrame> current = cv::rgbd::OdometryFrame::create(gray, frames[i].depth.clone());
    if (previous) {
      cv::Mat rt;  // maps current-frame points into the previous frame (src = current)
      bool ok = false;
      try {
        ok = odometry->compute(current, previous, rt, last_motion);
      } catch (const cv::Exception&) {
        ok = false;
      }
      if (ok) {
        last_motion = rt.clone();
        Eigen::Matrix4d m;
        cv::cv2eigen(rt, m);
        Pose step;
        step.matrix() = m;
        pose = orthonormalized(pose * step);
      } else {
        ++run.failures;
      }
    }
    previous = current;
    run.frame_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    run.trajectory.push_back({frames[i].timestamp, pose});
  }
  return run;
}

}  // namespace semap::baseline
#endif
