#include "tracking/lost_frame_poses.hpp"

#include <algorithm>
#include <optional>

#include "semap/core/error.hpp"

namespace semap {

void fill_lost_poses(Trajectory& trajectory, const std::vector<bool>& verified, double max_gap_s) {
  if (verified.size() != trajectory.size()) throw Error("fill_lost_poses", "one verified flag per pose expected");
  if (max_gap_s <= 0) return;
  // One pass back for each pose's next verified pose, one forward for its previous one.
  std::vector<std::optional<size_t>> next_verified(trajectory.size());
  std::optional<size_t> next;
  for (size_t i = trajectory.size(); i-- > 0;) {
    next_verified[i] = next;
    if (verified[i]) next = i;
  }
  std::optional<size_t> previous;
  for (size_t i = 0; i < trajectory.size(); ++i) {
    if (verified[i]) {
      previous = i;
      continue;
    }
    const std::optional<size_t> b = next_verified[i];
    if (!previous || !b) continue;  // before the first or after the last verified one: held
    const double t_a = trajectory[*previous].timestamp, t_b = trajectory[*b].timestamp;
    if (t_b <= t_a || t_b - t_a > max_gap_s) continue;
    const double s = std::clamp((trajectory[i].timestamp - t_a) / (t_b - t_a), 0.0, 1.0);  // stamps out of order
    trajectory[i].T_world_camera = interpolate_pose(trajectory[*previous].T_world_camera, trajectory[*b].T_world_camera, s);
  }
}

}  // namespace semap
