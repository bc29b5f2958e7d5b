#include "tracking/lost_frame_poses.hpp"

#include <optional>

namespace semap {
namespace {

/// The verified sample nearest before index i, or none.
std::optional<size_t> verified_before(const std::vector<TrajectorySample>& samples, size_t i) {
  while (i-- > 0)
    if (samples[i].verified) return i;
  return std::nullopt;
}

std::optional<size_t> verified_after(const std::vector<TrajectorySample>& samples, size_t i) {
  for (++i; i < samples.size(); ++i)
    if (samples[i].verified) return i;
  return std::nullopt;
}

}  // namespace

void fill_lost_poses(std::vector<TrajectorySample>& samples, double max_gap_s) {
  if (max_gap_s <= 0) return;
  for (size_t i = 0; i < samples.size(); ++i) {
    if (samples[i].verified) continue;
    const std::optional<size_t> a = verified_before(samples, i);
    if (!a) continue;
    const std::optional<size_t> b = verified_after(samples, i);
    if (!b) return;  // the lost frames after the last verified one stay held
    const double t_a = samples[*a].timestamp, t_b = samples[*b].timestamp;
    if (t_b <= t_a || t_b - t_a > max_gap_s) continue;
    const double s = (samples[i].timestamp - t_a) / (t_b - t_a);
    samples[i].T_world_camera = interpolate_pose(samples[*a].T_world_camera, samples[*b].T_world_camera, s);
  }
}

}  // namespace semap
