#pragma once
// Verification of a registration before it is trusted (issue 42; METHODS.md A2 "tracking
// loss"): independent evidence beside the ICP's own residual and the ORB inliers.
//   dense residual   the frame's depth warped into the reference with the candidate pose: the
//                    share of points that agree with the reference depth within its noise,
//                    against those the reference saw through (free-space violations);
//   inlier spread    grid cells of the image the RANSAC inliers occupy;
//   second hypothesis  the next-best distinct RANSAC model (repetitive structure);
//   conditioning     smallest eigenvalue of the frame geometry's point-to-plane information per
//                    point (plane-only scenes).
// Pure functions of their inputs: any thread.
#include <vector>

#include "semap/core/pose.hpp"
#include "semap/tracking/tracking_config.hpp"
#include "tracking/registration.hpp"

namespace semap {

/// Which checks a registration passed, with the measured values (thresholds: VerificationParams).
struct RegistrationCheck {
  bool evaluated = false;           ///< false: verification off or no ICP result to check
  // dense depth residual
  double consistent_fraction = 0;   ///< agreeing / (agreeing + free-space violations) of the warped points
  double dense_overlap = 0;         ///< warped points with reference depth / valid frame points
  double agreeing_share = 0;        ///< agreeing / warped points the reference saw
  int dense_points = 0;             ///< warped points the reference saw (the overlap)
  bool dense_ok = true;
  // inlier spread
  int occupied_cells = 0;
  bool spread_ok = true;
  // second hypothesis
  int runner_up_votes = 0;          ///< best distinct RANSAC model's votes (0: none)
  bool ambiguous = false;           ///< that model has nearly as many votes as the best
  // conditioning (evaluated only for a pose without trusted features, Odometry::judge)
  bool conditioning_evaluated = false;
  double min_information_eigenvalue = 0;
  bool well_conditioned = true;

  /// The features may overrule the motion prior: spread and unambiguous.
  bool features_trustworthy() const { return spread_ok && !ambiguous; }
};

/// Depth noise sigma at depth z (VerificationParams' sensor model), metres.
double depth_noise_sigma(double z_m, const VerificationParams& params);

struct DenseResidual {
  int valid = 0;       ///< valid frame points visited
  int overlap = 0;     ///< of those, projected onto valid reference depth
  int agreeing = 0;    ///< within the noise bound
  int violating = 0;   ///< nearer than the reference surface by more than the bound (its free space)
  /// agreeing / (agreeing + violating). Points behind the reference surface are not evidence
  /// (counting them against the pose rejected right poses on fr1_rpy and redkitchen: 0.35-0.5).
  double consistent_fraction() const { return agreeing + violating > 0 ? double(agreeing) / (agreeing + violating) : 0.0; }
  double overlap_fraction() const { return valid > 0 ? double(overlap) / valid : 0.0; }
  /// agreeing / overlap: how much of what the pose puts in view of the reference it explains.
  double agreeing_share() const { return overlap > 0 ? double(agreeing) / overlap : 0.0; }
};
/// Warps `frame`'s vertices with T_ref_frame into `reference` (projective association, same
/// pyramid level, the best of a 3x3 neighbourhood: depth edges) and compares depths.
DenseResidual dense_depth_residual(const DepthLevel& frame, const DepthLevel& reference, const Pose& T_ref_frame,
                                   const VerificationParams& params);

/// Cells of a grid x grid partition of a width x height image that hold at least one point.
int occupied_grid_cells(const std::vector<cv::Point2f>& points, int width, int height, int grid);

/// Votes of the best sampled RANSAC model that is distinct from the result (0 when none):
/// fewer than half of its votes come from the result's inliers, so it explains the frame with
/// other matches (repetitive structure matched to the wrong copy). `src`, `dst`: the matched
/// points RANSAC ran on; models with fewer than `min_votes` are not looked at (cost).
int ransac_runner_up(const RansacResult& ransac, const std::vector<Eigen::Vector3d>& src,
                     const std::vector<Eigen::Vector3d>& dst, double inlier_distance_m, int min_votes = 0);

/// Point-to-plane information sum J^T J, J = (p x n, n), of a pyramid level's own vertices and
/// normals (rotation, translation order): how well the level's geometry constrains a pose.
Matrix6d point_to_plane_information(const DepthLevel& level);

/// Smallest eigenvalue of the point-to-plane information (rotation, translation order) per
/// matched point, the rotation block scaled by the scene's lever sqrt(tr H_rr / tr H_tt): 1/3 for
/// points on three orthogonal planes, ~0 for one plane (sliding and spinning in it are free).
double scaled_min_information_eigenvalue(const Matrix6d& hessian);

}  // namespace semap
