#pragma once
// SE(3) poses. Convention (ARCHITECTURE.md): poses are T_world_camera (camera-to-world),
// metres, seconds.
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace semap {

using Pose = Eigen::Isometry3d;

/// A timestamped pose, one line of a TUM trajectory.
struct StampedPose {
  double timestamp = 0.0;
  Pose T_world_camera = Pose::Identity();
};
using Trajectory = std::vector<StampedPose>;

/// Builds a pose from translation + quaternion (x, y, z, w as in TUM files).
Pose pose_from_tq(const Eigen::Vector3d& t, const Eigen::Quaterniond& q);

/// True when every entry is finite and the rotation is orthonormal within tol.
bool is_valid_pose(const Pose& pose, double tol = 1e-6);

/// Rotation angle of a pose's rotation part in radians.
double rotation_angle(const Pose& pose);

/// Orthonormalises the rotation part (removes numerical drift after many compositions).
Pose orthonormalized(const Pose& pose);

/// The pose a fraction s of the way from a to b: rotation by slerp, translation linearly.
/// s outside [0, 1] extrapolates along the same path (while the rotation stays below 180 deg).
Pose interpolate_pose(const Pose& a, const Pose& b, double s);

}  // namespace semap
