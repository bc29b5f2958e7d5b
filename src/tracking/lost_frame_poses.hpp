#pragma once
// Issue 42: the poses a trajectory reports for the frames tracking lost. track() holds a lost
// frame at the last verified pose (it cannot know the frames after it); once the sequence is
// done the verified frames around it tell more.
#include <vector>

#include "semap/core/pose.hpp"

namespace semap {

/// Replaces the held pose of each lost frame (verified[i] false) between two verified frames at most
/// max_gap_s apart by the pose interpolated between them by time. Lost frames before the first
/// or after the last verified frame stay held: a constant-velocity prediction past the last one
/// was measured worse than holding (redkitchen at keyframe rate turns back there: 11.4 -> 15.4
/// cm ATE). Poses in time order, one flag each; max_gap_s 0 changes nothing. Thread safety: a
/// pure function.
void fill_lost_poses(Trajectory& trajectory, const std::vector<bool>& verified, double max_gap_s);

}  // namespace semap
