#include "tracking/odometry.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "semap/core/error.hpp"
#include "tracking/pose_graph.hpp"  // information_from_icp

namespace semap {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
double deg(double rad) { return rad * 180.0 / M_PI; }
}  // namespace

double pose_distance(const Pose& a, const Pose& b) {
  const Pose d = a.inverse() * b;
  return d.translation().norm() + 0.5 * rotation_angle(d);
}

double keyframe_spacings(const Pose& relative, const TrackingConfig& c) {
  return relative.translation().norm() / c.keyframe_translation + deg(rotation_angle(relative)) / c.keyframe_rotation_deg;
}

Odometry::Odometry(const TrackingConfig& config, const PinholeIntrinsics& intrinsics)
    : cfg_(config), intr_(intrinsics) {
  const auto make_orb = [&](int features) {
    return cv::ORB::create(features, float(cfg_.orb_scale_factor), cfg_.orb_levels, 19, 0, 2, cv::ORB::HARRIS_SCORE,
                           31, cfg_.orb_fast_threshold);
  };
  orb_ = make_orb(cfg_.orb_features);
  if (cfg_.orb_wide_features > 0) wide_orb_ = make_orb(cfg_.orb_wide_features);
  icp_params_ = cfg_.icp;
  // Wide-baseline ICP (issue 16): twice the coarse iterations, the basin is at the coarse levels.
  wide_icp_params_ = cfg_.icp;
  wide_icp_params_.iterations_coarse = 2 * cfg_.icp.iterations_coarse;
  wide_icp_params_.iterations_mid = 2 * cfg_.icp.iterations_mid;
}

FrameFeatures Odometry::extract_features(const cv::Mat& gray, const cv::Mat& depth) {
  return semap::extract_features(*orb_, gray, depth, intr_, cfg_.min_depth, cfg_.max_depth);
}

FrameFeatures Odometry::extract_wide_features(const cv::Mat& gray, const cv::Mat& depth) {
  if (!wide_orb_) throw Error("Odometry", "tracking.orb_wide_features is 0: no wide-baseline feature set");
  return semap::extract_features(*wide_orb_, gray, depth, intr_, cfg_.min_depth, cfg_.max_depth);
}

std::vector<DepthLevel> Odometry::pyramid(const cv::Mat& depth, const cv::Mat& gray, bool source_only) const {
  return build_depth_pyramid(depth, intr_, cfg_.icp.levels, cfg_.min_depth, cfg_.max_depth, true,
                             cfg_.icp.photometric_weight > 0 ? gray : cv::Mat(), source_only);
}

IcpResult Odometry::refine(const std::vector<DepthLevel>& source, const std::vector<DepthLevel>& target,
                           const Pose& T_target_source) const {
  return icp_point_to_plane(source, target, T_target_source, icp_params_);
}

bool Odometry::icp_acceptable(const IcpResult& icp, double max_rmse, double min_overlap) const {
  return icp.converged && icp.rmse <= max_rmse && icp.overlap >= min_overlap;
}

bool Odometry::plausible(const Pose& prior, const Pose& T_ref_frame) const {
  const Pose jump = prior.inverse() * T_ref_frame;
  return jump.translation().norm() <= cfg_.loss_max_translation_jump &&
         deg(rotation_angle(jump)) <= cfg_.loss_max_rotation_jump_deg;
}

Matrix6d Odometry::information(const IcpResult& icp) const {
  return information_from_icp(icp.hessian, icp.T_target_source, icp.matched,
                              std::max(icp.rmse, cfg_.information_min_sigma), cfg_.information_effective_points);
}

/// Spread and second-model checks of a RANSAC estimate (issue 42): once per registration.
RegistrationCheck Odometry::check_features(const FrameFeatures& frame_features,
                                           const std::vector<std::pair<int, int>>& pairs,
                                           const std::vector<Eigen::Vector3d>& src,
                                           const std::vector<Eigen::Vector3d>& dst, const RansacResult& ransac) const {
  RegistrationCheck check;
  const VerificationParams& vp = cfg_.verify;
  if (!vp.enabled || !ransac.ok) return check;
  std::vector<cv::Point2f> inlier_pixels;
  inlier_pixels.reserve(ransac.inliers.size());
  for (int i : ransac.inliers) inlier_pixels.push_back(frame_features.keypoints[size_t(pairs[size_t(i)].first)].pt);
  check.occupied_cells = occupied_grid_cells(inlier_pixels, intr_.width, intr_.height, vp.spread_grid);
  check.spread_ok = check.occupied_cells >= vp.spread_min_cells;
  check.runner_up_votes = ransac_runner_up(ransac, src, dst, cfg_.ransac.inlier_distance,
                                          int(std::ceil(vp.ambiguity_vote_ratio * ransac.best_votes)));
  check.ambiguous = check.runner_up_votes >= vp.ambiguity_vote_ratio * ransac.best_votes;
  return check;
}

/// Dense depth residual and conditioning of an ICP result (issue 42).
void Odometry::verify(OdometryResult& reg, const Evidence& ev) const {
  const VerificationParams& vp = cfg_.verify;
  reg.check = ev.feature_check;
  if (!vp.enabled || reg.icp.matched == 0) return;
  const RegistrationCheck dense = dense_check(*ev.frame_pyramid, *ev.kf_pyramid, reg.icp.T_target_source);
  reg.check.evaluated = true;
  reg.check.consistent_fraction = dense.consistent_fraction;
  reg.check.dense_overlap = dense.dense_overlap;
  reg.check.dense_points = dense.dense_points;
  reg.check.agreeing_share = dense.agreeing_share;
  reg.check.dense_ok = dense.dense_ok;
}

RegistrationCheck Odometry::dense_check(const std::vector<DepthLevel>& frame_pyramid,
                                        const std::vector<DepthLevel>& ref_pyramid, const Pose& T_ref_frame) const {
  const VerificationParams& vp = cfg_.verify;
  RegistrationCheck check;
  if (!vp.enabled || frame_pyramid.empty() || ref_pyramid.empty()) return check;
  check.evaluated = true;
  const int last = int(std::min(frame_pyramid.size(), ref_pyramid.size())) - 1;
  const size_t level = size_t(std::min<int>(vp.residual_level, last));
  const DenseResidual dense = dense_depth_residual(frame_pyramid[level], ref_pyramid[level], T_ref_frame, vp);
  check.consistent_fraction = dense.consistent_fraction();
  check.dense_overlap = dense.overlap_fraction();
  check.dense_points = dense.overlap;
  check.agreeing_share = dense.agreeing_share();
  check.dense_ok = check.consistent_fraction >= vp.min_consistent_fraction && check.agreeing_share >= vp.min_agreeing_share;
  return check;
}

/// Conditioning of the frame's geometry (issue 42), at the coarsest pyramid level (its normals
/// are smooth enough to tell one plane from a room; level 0's are mostly Kinect noise).
void Odometry::check_conditioning(OdometryResult& reg, const Evidence& ev) const {
  reg.check.conditioning_evaluated = true;
  reg.check.min_information_eigenvalue = scaled_min_information_eigenvalue(point_to_plane_information(ev.frame_pyramid->back()));
  reg.check.well_conditioned = reg.check.min_information_eigenvalue >= cfg_.verify.min_information_eigenvalue;
}

/// Judges an ICP result (issue 16, verified as issue 42 asks): converged with acceptable
/// residual and overlap, and its dense depth residual agrees; trusted when a well-supported,
/// spread, unambiguous RANSAC estimate agrees with it, else it must be plausible against the
/// prior and the frame's geometry well conditioned (without a prior: not accepted).
void Odometry::judge(OdometryResult& reg, const Evidence& ev, const Pose* prior) const {
  reg.T_kf_frame = reg.icp.T_target_source;
  reg.ok = icp_acceptable(reg.icp, cfg_.loss_max_icp_rmse, cfg_.loss_min_overlap);
  if (reg.ok) verify(reg, ev);
  reg.feature_supported = ev.trusted && pose_distance(ev.ransac->T, reg.T_kf_frame) <= cfg_.ransac.icp_agreement;
  bool prior_supported = prior && plausible(*prior, reg.T_kf_frame);
  // Only a pose the features do not pin down needs the geometry to (computed only then: cost).
  if (reg.ok && reg.check.dense_ok && !reg.feature_supported && prior_supported && reg.check.evaluated) {
    check_conditioning(reg, ev);
    prior_supported = reg.check.well_conditioned;
  }
  reg.accepted = reg.ok && reg.check.dense_ok && (reg.feature_supported || prior_supported);
}

/// The wide-baseline ICP gate: grows with how far the start may be off (the prior's own step).
IcpParams Odometry::wide_params(double expected_error_m) const {
  IcpParams p = wide_icp_params_;
  p.max_distance = std::clamp(cfg_.wide_icp_gate_factor * expected_error_m, cfg_.icp.max_distance,
                              std::max(cfg_.icp.max_distance, cfg_.wide_icp_max_distance));
  return p;
}

OdometryResult Odometry::register_to(const FrameFeatures& frame_features, const std::vector<DepthLevel>& frame_pyramid,
                                     const FrameFeatures& kf_features, const std::vector<DepthLevel>& kf_pyramid,
                                     const Pose* prior, uint32_t seed, RegistrationEffort effort,
                                     double prior_step_m) const {
  const bool wide = effort == RegistrationEffort::wide;
  OdometryResult reg;
  auto t0 = Clock::now();
  const auto pairs = match_features(frame_features, kf_features, cfg_.match_ratio, cfg_.match_max_hamming);
  reg.matches = int(pairs.size());
  std::vector<Eigen::Vector3d> src, dst;
  for (const auto& [q, t] : pairs) {
    src.push_back(frame_features.points[q]);
    dst.push_back(kf_features.points[t]);
  }
  RansacParams rp = cfg_.ransac;
  if (wide) rp.iterations = cfg_.ransac.wide_iterations;
  rp.seed = seed;
  const RansacResult ransac = ransac_rigid(src, dst, rp);
  reg.inliers = ransac.ok ? int(ransac.inliers.size()) : 0;
  Evidence ev;
  ev.ransac = &ransac;
  ev.feature_check = check_features(frame_features, pairs, src, dst, ransac);
  ev.trusted = ransac.ok && reg.inliers >= cfg_.ransac.trusted_inliers &&
               reg.inliers >= cfg_.ransac.trusted_ratio * reg.matches && ev.feature_check.features_trustworthy();
  ev.frame_pyramid = &frame_pyramid;
  ev.kf_pyramid = &kf_pyramid;
  reg.ransac_ms = ms_since(t0);
  t0 = Clock::now();
  const IcpParams& params = wide ? wide_icp_params_ : icp_params_;
  if (ransac.ok) {
    reg.icp = icp_point_to_plane(frame_pyramid, kf_pyramid, ransac.T, params);
    judge(reg, ev, prior);
  }
  // RANSAC on a few bad matches can mislead ICP; the prior is the second chance.
  if (!reg.accepted && prior) {
    OdometryResult second = reg;
    second.icp = icp_point_to_plane(frame_pyramid, kf_pyramid, *prior, wide ? wide_params(prior_step_m) : icp_params_);
    judge(second, ev, prior);
    second.used_prior = true;
    if (second.accepted || !ransac.ok) reg = second;
  }
  if (reg.icp.matched > 0) reg.information = information(reg.icp);
  reg.icp_ms = ms_since(t0);
  return reg;
}

}  // namespace semap
