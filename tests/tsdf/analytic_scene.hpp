#pragma once
// A hand-made analytic scene for TSDF tests: a sphere (chair) in front of a wall (plane z = 3)
// and a floor (plane y = 0.6), ray-cast exactly into depth + label images.
#include <cmath>
#include <opencv2/core.hpp>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/labels.hpp"
#include "semap/core/pose.hpp"

namespace semap::test {

struct AnalyticScene {
  Eigen::Vector3d sphere_centre{0.0, 0.1, 2.0};
  double sphere_radius = 0.4;
  double wall_z = 3.0;
  double floor_y = 0.6;  // camera y points down

  /// Distance from p to the nearest true surface.
  double distance(const Eigen::Vector3d& p) const {
    return std::min({std::fabs((p - sphere_centre).norm() - sphere_radius), std::fabs(p.z() - wall_z),
                     std::fabs(p.y() - floor_y)});
  }
  ClassId label_at(const Eigen::Vector3d& p) const {
    const double ds = std::fabs((p - sphere_centre).norm() - sphere_radius);
    const double dw = std::fabs(p.z() - wall_z), df = std::fabs(p.y() - floor_y);
    if (ds <= dw && ds <= df) return id(Label::kChair);
    return dw <= df ? id(Label::kWall) : id(Label::kFloor);
  }
  /// Ray-casts depth (metres) and labels for a camera pose.
  void render(const PinholeIntrinsics& K, const Pose& T_world_camera, cv::Mat& depth, cv::Mat& labels) const {
    depth.create(K.height, K.width, CV_32FC1);
    labels.create(K.height, K.width, CV_8UC1);
    const Eigen::Matrix3d R = T_world_camera.linear();
    const Eigen::Vector3d o = T_world_camera.translation();
    for (int v = 0; v < K.height; ++v)
      for (int u = 0; u < K.width; ++u) {
        const Eigen::Vector3d dc((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);  // z = 1 ray
        const Eigen::Vector3d d = R * dc;
        double best = 1e9;
        ClassId label = 0;
        // Sphere.
        const Eigen::Vector3d oc = o - sphere_centre;
        const double a = d.squaredNorm(), b = 2 * oc.dot(d), c = oc.squaredNorm() - sphere_radius * sphere_radius;
        const double disc = b * b - 4 * a * c;
        if (disc >= 0) {
          const double t = (-b - std::sqrt(disc)) / (2 * a);
          if (t > 0 && t < best) best = t, label = id(Label::kChair);
        }
        if (std::fabs(d.z()) > 1e-9) {
          const double t = (wall_z - o.z()) / d.z();
          if (t > 0 && t < best) best = t, label = id(Label::kWall);
        }
        if (std::fabs(d.y()) > 1e-9) {
          const double t = (floor_y - o.y()) / d.y();
          if (t > 0 && t < best) best = t, label = id(Label::kFloor);
        }
        // t along a z=1 camera ray is the camera depth.
        depth.at<float>(v, u) = best < 1e8 ? static_cast<float>(best) : 0.0f;
        labels.at<uint8_t>(v, u) = label;
      }
  }
  static std::vector<Pose> poses(int n) {
    std::vector<Pose> out;
    for (int i = 0; i < n; ++i) {
      const double a = 0.25 * std::sin(2 * M_PI * i / n);
      Pose T = Pose::Identity();
      T.linear() = Eigen::AngleAxisd(0.3 * a, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                   Eigen::AngleAxisd(0.05 * std::cos(2 * M_PI * i / n), Eigen::Vector3d::UnitX()).toRotationMatrix();
      T.translation() = Eigen::Vector3d(a, 0.05 * std::cos(2 * M_PI * i / n), 0.1 * i / n);
      out.push_back(T);
    }
    return out;
  }
  static PinholeIntrinsics intrinsics() {
    PinholeIntrinsics K;
    K.width = 320;
    K.height = 240;
    K.fx = K.fy = 262.5;
    K.cx = 159.5;
    K.cy = 119.5;
    return K;
  }
};

}  // namespace semap::test
