#include "semap/core/pose.hpp"

#include <cmath>

namespace semap {

Pose pose_from_tq(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
  Pose pose = Pose::Identity();
  pose.linear() = q.normalized().toRotationMatrix();
  pose.translation() = t;
  return pose;
}

bool is_valid_pose(const Pose& pose, double tol) {
  if (!pose.matrix().allFinite()) return false;
  const Eigen::Matrix3d r = pose.linear();
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > tol) return false;
  return std::abs(r.determinant() - 1.0) < tol;
}

double rotation_angle(const Pose& pose) {
  const double c = std::clamp((pose.linear().trace() - 1.0) * 0.5, -1.0, 1.0);
  return std::acos(c);
}

Pose orthonormalized(const Pose& pose) {
  Pose out = pose;
  out.linear() = Eigen::Quaterniond(pose.linear()).normalized().toRotationMatrix();
  return out;
}

Pose interpolate_pose(const Pose& a, const Pose& b, double s) {
  Pose out = Pose::Identity();
  out.linear() = Eigen::Quaterniond(a.linear()).slerp(s, Eigen::Quaterniond(b.linear())).normalized().toRotationMatrix();
  out.translation() = (1 - s) * a.translation() + s * b.translation();
  return out;
}

}  // namespace semap
