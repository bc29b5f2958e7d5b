#include "tracking/lost_frame_poses.hpp"

#include <algorithm>
#include <optional>

namespace semap {

void fill_lost_poses(std::vector<TrajectorySample>& samples, double max_gap_s) {
  if (max_gap_s <= 0) return;
  // One pass back for each sample's next verified sample, one forward for its previous one.
  std::vector<std::optional<size_t>> next_verified(samples.size());
  std::optional<size_t> next;
  for (size_t i = samples.size(); i-- > 0;) {
    next_verified[i] = next;
    if (samples[i].verified) next = i;
  }
  std::optional<size_t> previous;
  for (size_t i = 0; i < samples.size(); ++i) {
    if (samples[i].verified) {
      previous = i;
      continue;
    }
    const std::optional<size_t> b = next_verified[i];
    if (!previous || !b) continue;  // before the first or after the last verified one: held
    const double t_a = samples[*previous].timestamp, t_b = samples[*b].timestamp;
    if (t_b <= t_a || t_b - t_a > max_gap_s) continue;
    const double s = std::clamp((samples[i].timestamp - t_a) / (t_b - t_a), 0.0, 1.0);  // stamps out of order
    samples[i].T_world_camera = interpolate_pose(samples[*previous].T_world_camera, samples[*b].T_world_camera, s);
  }
}

}  // namespace semap
