#pragma once
// The synthetic camera path: one closed loop (an ellipse around the room centre, looking
// outwards at the furniture along the walls) with smooth height, yaw, pitch and roll
// oscillations. Every quantity is a periodic function of the loop angle, so the last frame
// is one step before the first and the start view is revisited (loop-closure tests).
#include <Eigen/Core>

#include "semap/core/pose.hpp"

namespace semap {

struct LoopTrajectoryParams {
  double mean_height = 1.4;    ///< m
  double height_amplitude = 0.1;
  double wall_clearance_x = 1.8;  ///< m from the ellipse to the +-x walls
  double wall_clearance_y = 1.7;  ///< m from the ellipse to the +-y walls
  double pitch_deg = -25.0;    ///< mean pitch (negative = looking down)
  double pitch_amplitude_deg = 6.0;
  double yaw_amplitude_deg = 14.0;
  double roll_amplitude_deg = 2.0;
  double start_time = 0.0;     ///< s, timestamp of frame 0
};

/// T_world_camera of frame i of n (camera x right, y down, z forward; world z up).
Pose loop_pose(const Eigen::Vector3d& room_size, int i, int n, const LoopTrajectoryParams& params = {});
/// The whole loop, timestamps start_time + i / fps.
Trajectory make_loop_trajectory(const Eigen::Vector3d& room_size, int frames, double fps,
                                const LoopTrajectoryParams& params = {});

}  // namespace semap
