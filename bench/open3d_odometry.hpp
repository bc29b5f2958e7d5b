#pragma once
// Open3D's RGB-D odometry (hybrid photometric + geometric term, frame to frame): the
// comparison baseline of issue 4, shared by bench_tracking and the heavy tracking test.
// Only available when the build found Open3D (SEMAP_HAVE_OPEN3D).
#ifdef SEMAP_HAVE_OPEN3D
#include <open3d/camera/PinholeCameraIntrinsic.h>
#include <open3d/geometry/Image.h>
#include <open3d/geometry/RGBDImage.h>
#include <open3d/pipelines/odometry/Odometry.h>

#include <chrono>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"
#include "semap/core/pose.hpp"

namespace semap::baseline {

struct Open3dOdometryRun {
  Trajectory trajectory;           ///< one pose per frame (a failed step keeps the last pose)
  std::vector<double> frame_ms;    ///< wall time per frame
  size_t failures = 0;
};

/// Chains Open3D's ComputeRGBDOdometry (hybrid Jacobian, pyramid iterations {20, 10, 5},
/// depth in [0, 4] m, last motion as initial guess) over the frames.
inline Open3dOdometryRun run_open3d_odometry(const std::vector<Frame>& frames, const CameraModel& camera) {
  namespace o3 = open3d;
  const auto& k = camera.depth;
  o3::camera::PinholeCameraIntrinsic intrinsic(k.width, k.height, k.fx, k.fy, k.cx, k.cy);
  auto to_rgbd = [](const Frame& f) {
    cv::Mat gray, grayf;
    cv::cvtColor(f.rgb, gray, cv::COLOR_BGR2GRAY);
    if (gray.size() != f.depth.size()) cv::resize(gray, gray, f.depth.size());
    gray.convertTo(grayf, CV_32F, 1.0 / 255.0);
    o3::geometry::Image intensity, depth;
    intensity.Prepare(grayf.cols, grayf.rows, 1, 4);
    depth.Prepare(f.depth.cols, f.depth.rows, 1, 4);
    std::memcpy(intensity.data_.data(), grayf.data, intensity.data_.size());
    cv::Mat d = f.depth.isContinuous() ? f.depth : f.depth.clone();
    std::memcpy(depth.data_.data(), d.data, depth.data_.size());
    return o3::geometry::RGBDImage(intensity, depth);
  };
  Open3dOdometryRun run;
  Pose pose = Pose::Identity();
  Eigen::Matrix4d last_motion = Eigen::Matrix4d::Identity();
  o3::geometry::RGBDImage previous;
  for (size_t i = 0; i < frames.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    o3::geometry::RGBDImage current = to_rgbd(frames[i]);
    if (i > 0) {
      o3::pipelines::odometry::OdometryOption option({20, 10, 5}, 0.07, 0.0, 4.0);
      const auto [ok, t_prev_cur, info] = o3::pipelines::odometry::ComputeRGBDOdometry(
          current, previous, intrinsic, last_motion,
          o3::pipelines::odometry::RGBDOdometryJacobianFromHybridTerm(), option);
      if (ok) {
        last_motion = t_prev_cur;
        Pose step;
        step.matrix() = t_prev_cur;
        pose = orthonormalized(pose * step);
      } else {
        ++run.failures;
      }
    }
    previous = std::move(current);
    run.frame_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    run.trajectory.push_back({frames[i].timestamp, pose});
  }
  return run;
}

}  // namespace semap::baseline
#endif
