#pragma once
// Synthetic scenes of the tracking unit tests: a pose from Euler angles and a ray-cast box room.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "semap/core/camera.hpp"
#include "semap/core/pose.hpp"

namespace semap::test {

inline Pose make_pose(double rx, double ry, double rz, double tx, double ty, double tz) {
  Pose p = Pose::Identity();
  p.linear() = (Eigen::AngleAxisd(rz, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(ry, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rx, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  p.translation() = Eigen::Vector3d(tx, ty, tz);
  return p;
}

// A box room (walls at x = +-2, y = +-1.5, z = -1 / 3.5) with a sphere and a slanted block, so
// every degree of freedom is constrained. Ray cast from a camera at T_world_camera.
inline cv::Mat render_room(const PinholeIntrinsics& k, const Pose& T_world_camera) {
  cv::Mat depth(k.height, k.width, CV_32FC1, cv::Scalar(0));
  const Eigen::Vector3d o = T_world_camera.translation();
  const Eigen::Matrix3d r = T_world_camera.linear();
  const Eigen::Vector3d sphere(0.6, 0.3, 2.2);
  const double radius = 0.45;
  const Eigen::Vector3d slant_n = Eigen::Vector3d(1, 1, 1).normalized();
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d dc((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);  // z = 1: t is depth
      const Eigen::Vector3d d = r * dc;
      double best = 1e9;
      auto plane = [&](int axis, double value) {
        if (std::abs(d[axis]) < 1e-12) return;
        const double t = (value - o[axis]) / d[axis];
        if (t > 0) best = std::min(best, t);
      };
      plane(0, -2.0), plane(0, 2.0), plane(1, -1.5), plane(1, 1.5), plane(2, -1.0), plane(2, 3.5);
      // Sphere.
      const Eigen::Vector3d oc = o - sphere;
      const double a = d.squaredNorm(), b = 2 * oc.dot(d), c = oc.squaredNorm() - radius * radius;
      const double disc = b * b - 4 * a * c;
      if (disc > 0) {
        const double t = (-b - std::sqrt(disc)) / (2 * a);
        if (t > 0) best = std::min(best, t);
      }
      // Slanted plane patch near the left-bottom corner.
      const double denom = slant_n.dot(d);
      if (std::abs(denom) > 1e-9) {
        const double t = (slant_n.dot(Eigen::Vector3d(-1.2, 0.8, 2.6)) - slant_n.dot(o)) / denom;
        const Eigen::Vector3d p = o + t * d;
        if (t > 0 && p.x() < -0.6 && p.y() > 0.2 && p.z() < 3.3) best = std::min(best, t);
      }
      if (best < 1e8) depth.at<float>(v, u) = float(best);
    }
  }
  return depth;
}

}  // namespace semap::test
