#pragma once
// Trajectory metrics with the TUM RGB-D benchmark's definitions (METHODS.md D):
// ATE as in evaluate_ate.py, RPE as in evaluate_rpe.py (fixed delta in seconds).
#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

#include "semap/core/pose.hpp"

namespace semap {

/// Absolute trajectory error. Statistics are over the translation differences
/// |T_gt_est * p_est - p_gt| of the associated pairs, in metres.
struct AteResult {
  double rmse = 0.0, mean = 0.0, median = 0.0, max = 0.0;
  size_t matched = 0;               ///< associated pose pairs used
  Pose T_gt_est = Pose::Identity();  ///< rigid alignment mapping est positions onto gt
  /// (estimated pose timestamp s, error m) of each associated pair, in estimate order: the
  /// "ATE over time" plot of report.html (issue 43). Not in to_json (report.json "frames").
  std::vector<std::pair<double, double>> per_pose_error_m;
};

/// 1. Associates timestamps (greedy one-to-one, |t_gt - t_est| < max_dt, associate.py).
/// 2. Aligns the est positions to the gt positions with Horn/Umeyama SE(3), no scale.
/// 3. Statistics of the remaining translation differences.
/// Throws semap::Error when fewer than 3 pairs associate (alignment undefined).
AteResult compute_ate(const Trajectory& gt, const Trajectory& est, double max_dt = 0.02);

/// Relative pose error over a fixed time delta, normalised to rates.
struct RpeResult {
  double trans_rmse_m_per_s = 0.0;    ///< RMSE of per-pair translational error / elapsed time
  double rot_rmse_deg_per_s = 0.0;    ///< RMSE of per-pair rotation angle / elapsed time
  double trans_mean_m_per_s = 0.0;
  double rot_mean_deg_per_s = 0.0;
  size_t pairs = 0;
  /// Why no pair qualified (pairs == 0): the rates are then undefined, not 0 (a perfect score);
  /// to_json writes them as null with this reason.
  std::string no_pairs_reason;
};

/// Pairs (evaluate_rpe.py --fixed_delta --delta 1 --delta_unit s, made deterministic):
/// - est poses are associated to gt poses as in compute_ate (max_dt); only associated est
///   poses take part, in timestamp order;
/// - for every such pose i, j is the associated pose whose timestamp is closest to
///   t_i + delta_s; the pair is kept when j > i and |t_j - (t_i + delta_s)| <= max(max_dt,
///   half the median spacing of the associated est timestamps)
///   (no random subsampling, every pair kept);
/// - error E = (gt_i^-1 gt_j)^-1 (est_i^-1 est_j) (Sturm et al. 2012, eq. 1); the pair's
///   translational error |t(E)| and rotation angle of E are divided by the pair's elapsed
///   est time t_j - t_i, giving m/s and deg/s (equal to the benchmark's per-delta figures
///   for delta = 1 s up to the sampling jitter).
/// Returns pairs = 0, zero rates and no_pairs_reason when no pair qualifies (sequence shorter
/// than delta).
RpeResult compute_rpe(const Trajectory& gt, const Trajectory& est, double delta_s = 1.0,
                      double max_dt = 0.02);

nlohmann::json to_json(const AteResult& ate);
nlohmann::json to_json(const RpeResult& rpe);

}  // namespace semap
