#include "semap/eval/trajectory_metrics.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "semap/core/error.hpp"
#include "core/statistics.hpp"
#include "io/association.hpp"

namespace semap {
namespace {

std::vector<double> timestamps_of(const Trajectory& trajectory) {
  std::vector<double> stamps;
  stamps.reserve(trajectory.size());
  for (const auto& p : trajectory) stamps.push_back(p.timestamp);
  return stamps;
}

void check_finite(const Trajectory& trajectory, const char* which) {
  for (size_t i = 0; i < trajectory.size(); ++i) {
    if (!std::isfinite(trajectory[i].timestamp) || !trajectory[i].T_world_camera.matrix().allFinite())
      throw Error(which, "pose " + std::to_string(i) + " is not finite");
  }
}


// Rotation angle via atan2(sin, cos): accurate near 0, unlike acos of the trace.
double rotation_angle_precise(const Pose& pose) {
  const Eigen::Matrix3d& R = pose.linear();
  const Eigen::Vector3d axis_sin(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  return std::atan2(0.5 * axis_sin.norm(), 0.5 * (R.trace() - 1.0));
}

}  // namespace

AteResult compute_ate(const Trajectory& gt, const Trajectory& est, double max_dt) {
  check_finite(gt, "ground-truth trajectory");
  check_finite(est, "estimated trajectory");
  // METHODS.md D: associate -> align (Horn/Umeyama, no scale) -> RMSE of translations.
  const auto matches = associate_timestamps(timestamps_of(gt), timestamps_of(est), max_dt);
  if (matches.size() < 3)
    throw Error("ATE", "only " + std::to_string(matches.size()) +
                           " poses associate within " + compact_number(max_dt) +
                           " s (need >= 3); are these the right files?");

  Eigen::Matrix3Xd est_positions(3, matches.size()), gt_positions(3, matches.size());
  for (size_t k = 0; k < matches.size(); ++k) {
    gt_positions.col(k) = gt[matches[k].first].T_world_camera.translation();
    est_positions.col(k) = est[matches[k].second].T_world_camera.translation();
  }
  AteResult result;
  result.matched = matches.size();
  const Eigen::Matrix4d T = Eigen::umeyama(est_positions, gt_positions, /*with_scaling=*/false);
  result.T_gt_est.matrix() = T;

  std::vector<double> errors(matches.size());
  double sum = 0.0, sum_sq = 0.0;
  for (size_t k = 0; k < matches.size(); ++k) {
    const double e = (result.T_gt_est * Eigen::Vector3d(est_positions.col(k)) - gt_positions.col(k)).norm();
    errors[k] = e;
    result.per_pose_error_m.emplace_back(est[matches[k].second].timestamp, e);
    sum += e;
    sum_sq += e * e;
    result.max = std::max(result.max, e);
  }
  const double n = static_cast<double>(matches.size());
  result.rmse = std::sqrt(sum_sq / n);
  result.mean = sum / n;
  result.median = median_of(std::move(errors));
  return result;
}

RpeResult compute_rpe(const Trajectory& gt, const Trajectory& est, double delta_s, double max_dt) {
  if (!(delta_s > 0.0) || !std::isfinite(delta_s)) throw Error("RPE", "delta must be > 0 s");
  check_finite(gt, "ground-truth trajectory");
  check_finite(est, "estimated trajectory");
  auto matches = associate_timestamps(timestamps_of(gt), timestamps_of(est), max_dt);
  // Timestamp order of the est side (the association returns pairs sorted by gt index).
  std::sort(matches.begin(), matches.end(), [&](const auto& a, const auto& b) {
    return est[a.second].timestamp < est[b.second].timestamp;
  });
  std::vector<double> stamps;
  stamps.reserve(matches.size());
  for (const auto& m : matches) stamps.push_back(est[m.second].timestamp);

  RpeResult result;
  double trans_sq = 0.0, rot_sq = 0.0, trans_sum = 0.0, rot_sum = 0.0;
  // Allowed mismatch of t_j against t_i + delta: half the median frame spacing (the nearest
  // frame on a regular grid is always within it), at least max_dt.
  std::vector<double> spacing;
  for (size_t k = 1; k < stamps.size(); ++k) spacing.push_back(stamps[k] - stamps[k - 1]);
  const double tolerance = std::max(max_dt, 0.5 * median_of(std::move(spacing)));
  for (size_t i = 0; i < stamps.size(); ++i) {
    const double target = stamps[i] + delta_s;
    // Closest associated est timestamp to t_i + delta.
    auto it = std::lower_bound(stamps.begin(), stamps.end(), target);
    size_t j = static_cast<size_t>(it - stamps.begin());
    if (j == stamps.size() || (j > 0 && target - stamps[j - 1] < stamps[j] - target)) --j;
    if (j <= i || std::abs(stamps[j] - target) > tolerance) continue;
    const double elapsed = stamps[j] - stamps[i];
    const Pose& gi = gt[matches[i].first].T_world_camera;
    const Pose& gj = gt[matches[j].first].T_world_camera;
    const Pose& ei = est[matches[i].second].T_world_camera;
    const Pose& ej = est[matches[j].second].T_world_camera;
    const Pose error = (gi.inverse() * gj).inverse() * (ei.inverse() * ej);
    const double trans = error.translation().norm() / elapsed;
    const double rot = rotation_angle_precise(error) * 180.0 / M_PI / elapsed;
    trans_sq += trans * trans;
    rot_sq += rot * rot;
    trans_sum += trans;
    rot_sum += rot;
    ++result.pairs;
  }
  if (result.pairs == 0) {
    const double span = stamps.size() > 1 ? stamps.back() - stamps.front() : 0.0;
    result.no_pairs_reason = stamps.size() < 2
                                 ? std::to_string(stamps.size()) + " poses associate with the ground truth (need 2)"
                                 : "no two associated poses are " + compact_number(delta_s) + " s apart (they span " +
                                       compact_number(span) + " s)";
  } else {
    const double n = static_cast<double>(result.pairs);
    result.trans_rmse_m_per_s = std::sqrt(trans_sq / n);
    result.rot_rmse_deg_per_s = std::sqrt(rot_sq / n);
    result.trans_mean_m_per_s = trans_sum / n;
    result.rot_mean_deg_per_s = rot_sum / n;
  }
  return result;
}

nlohmann::json to_json(const AteResult& ate) {
  nlohmann::json T = nlohmann::json::array();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) T.push_back(ate.T_gt_est.matrix()(r, c));
  return {{"rmse_m", ate.rmse},     {"mean_m", ate.mean}, {"median_m", ate.median},
          {"max_m", ate.max},       {"matched", ate.matched},
          {"T_gt_est", T}};
}

nlohmann::json to_json(const RpeResult& rpe) {
  if (rpe.pairs == 0)
    return {{"trans_rmse_m_per_s", nullptr}, {"rot_rmse_deg_per_s", nullptr}, {"trans_mean_m_per_s", nullptr},
            {"rot_mean_deg_per_s", nullptr}, {"pairs", 0}, {"reason", rpe.no_pairs_reason}};
  return {{"trans_rmse_m_per_s", rpe.trans_rmse_m_per_s},
          {"rot_rmse_deg_per_s", rpe.rot_rmse_deg_per_s},
          {"trans_mean_m_per_s", rpe.trans_mean_m_per_s},
          {"rot_mean_deg_per_s", rpe.rot_mean_deg_per_s},
          {"pairs", rpe.pairs}};
}

}  // namespace semap
