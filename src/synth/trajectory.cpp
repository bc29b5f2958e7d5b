#include "synth/trajectory.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "semap/core/error.hpp"

namespace semap {

Pose loop_pose(const Eigen::Vector3d& room, int i, int n, const LoopTrajectoryParams& p) {
  constexpr double kPi = 3.14159265358979323846, kDeg = kPi / 180.0;
  const double theta = 2.0 * kPi * i / std::max(1, n);
  const double a = std::max(0.2, room.x() / 2 - p.wall_clearance_x);
  const double b = std::max(0.2, room.y() / 2 - p.wall_clearance_y);
  const Eigen::Vector3d position(room.x() / 2 + a * std::cos(theta), room.y() / 2 + b * std::sin(theta),
                                 p.mean_height + p.height_amplitude * std::sin(2 * theta));
  const double yaw = theta + p.yaw_amplitude_deg * kDeg * std::sin(3 * theta);
  const double pitch = (p.pitch_deg + p.pitch_amplitude_deg * std::sin(5 * theta + 0.7)) * kDeg;
  const double roll = p.roll_amplitude_deg * kDeg * std::sin(4 * theta + 1.3);
  const Eigen::Vector3d forward(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch), std::sin(pitch));
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  Eigen::Matrix3d R;
  R.col(0) = right;
  R.col(1) = down;
  R.col(2) = forward;
  R = R * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Pose T = Pose::Identity();
  T.linear() = R;
  T.translation() = position;
  return T;
}

Trajectory make_loop_trajectory(const Eigen::Vector3d& room, int frames, double fps, const LoopTrajectoryParams& p) {
  if (frames < 1) throw Error("synth", "frames must be >= 1");
  if (!(fps > 0)) throw Error("synth", "fps must be > 0");
  Trajectory traj;
  traj.reserve(frames);
  for (int i = 0; i < frames; ++i) traj.push_back({p.start_time + i / fps, loop_pose(room, i, frames, p)});
  return traj;
}

}  // namespace semap
