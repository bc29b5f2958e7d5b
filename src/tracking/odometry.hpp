#pragma once
// Frame-to-keyframe odometry (METHODS.md A2): ORB features -> voting RANSAC -> point-to-plane
// (+ photometric) ICP, judged from the registration's own evidence. Stateless apart from the
// configuration: the tracker keeps the reference keyframe and the motion prior.
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/pose.hpp"
#include "semap/tracking/tracking_config.hpp"
#include "tracking/registration.hpp"
#include "tracking/registration_check.hpp"

namespace semap {

/// Outcome of registering a frame against a keyframe (A2).
struct OdometryResult {
  bool ok = false;                 ///< ICP converged with acceptable residual and overlap
  bool feature_supported = false;  ///< trusted RANSAC estimate (spread, unambiguous) that the ICP result agrees with
  /// ok, the dense residual agrees, and feature-supported or (well conditioned and plausible
  /// against the prior) (issue 42: verified before it is trusted)
  bool accepted = false;
  Pose T_kf_frame = Pose::Identity();  ///< the pose: frame camera in the keyframe's camera
  int matches = 0;                 ///< ORB matches
  int inliers = 0;                 ///< voting-RANSAC inliers (0 when RANSAC failed)
  bool used_prior = false;         ///< ICP started from the motion prior
  IcpResult icp;                   ///< the ICP that gave T_kf_frame (residual, overlap, Hessian)
  Matrix6d information = Matrix6d::Zero();  ///< of T_kf_frame, as a pose-graph edge (A4)
  RegistrationCheck check;         ///< the verification of T_kf_frame (issue 42)
  double ransac_ms = 0, icp_ms = 0;
  double overlap() const { return icp.overlap; }  ///< matched fraction of the frame's points
  double residual_m() const { return icp.rmse; }  ///< ICP point-to-plane RMSE, metres
};

/// How hard a registration tries: the per-frame path first, the wide-baseline one only when
/// that failed (issue 16: consecutive-frame speed stays as it was).
enum class RegistrationEffort { normal, wide };

/// Translation + rotation (radians x 0.5 m lever) distance of two poses, metres.
double pose_distance(const Pose& a, const Pose& b);
/// Pose distance in keyframe spacings: translation / keyframe_translation + rotation /
/// keyframe_rotation_deg (1 = the motion that makes a new keyframe).
double keyframe_spacings(const Pose& relative, const TrackingConfig& config);

/// Thread safety: the const methods read only the immutable configuration and may run on any
/// thread at once (the loop-closure worker and map merging use them beside track());
/// extract_features() uses the ORB detector's state: one thread (the tracking thread) only.
class Odometry {
 public:
  /// `config` must be validated (Tracker does).
  Odometry(const TrackingConfig& config, const PinholeIntrinsics& intrinsics);

  /// ORB keypoints with 3D points of a frame (A2 steps 1-2). Tracking thread only.
  FrameFeatures extract_features(const cv::Mat& gray, const cv::Mat& depth);
  /// The denser set of the wide-baseline attempt (tracking.orb_wide_features, which must be
  /// > 0). Tracking thread only.
  FrameFeatures extract_wide_features(const cv::Mat& gray, const cv::Mat& depth);
  /// ICP pyramid of a frame; `source_only` for a tracked frame (completed with
  /// complete_target_pyramid if it becomes a keyframe; METHODS.md A2 step 4).
  std::vector<DepthLevel> pyramid(const cv::Mat& depth, const cv::Mat& gray, bool source_only = false) const;

  /// A2: features -> voting RANSAC -> ICP from RANSAC, else (or when that is not accepted)
  /// from the prior (nullptr: none). `prior_step_m`: how far the prior may be off (its own
  /// step), for the wide-baseline gate.
  OdometryResult register_to(const FrameFeatures& frame_features, const std::vector<DepthLevel>& frame_pyramid,
                             const FrameFeatures& kf_features, const std::vector<DepthLevel>& kf_pyramid,
                             const Pose* prior, uint32_t seed,
                             RegistrationEffort effort = RegistrationEffort::normal, double prior_step_m = 0.0) const;
  /// ICP alone from a known start (keyframe re-use, local edges), the per-frame parameters.
  IcpResult refine(const std::vector<DepthLevel>& source, const std::vector<DepthLevel>& target,
                   const Pose& T_target_source) const;

  bool icp_acceptable(const IcpResult& icp, double max_rmse, double min_overlap) const;
  /// Dense depth residual check of `T_ref_frame` (issue 42): the frame's pyramid warped into the
  /// reference's at tracking.verify.residual_level. Not evaluated (and passing) when
  /// verification is off.
  RegistrationCheck dense_check(const std::vector<DepthLevel>& frame_pyramid, const std::vector<DepthLevel>& ref_pyramid,
                                const Pose& T_ref_frame) const;
  /// An estimate without trusted feature support must stay near the motion prior (A2).
  bool plausible(const Pose& prior, const Pose& T_ref_frame) const;
  /// Pose-graph information of an ICP result (A4).
  Matrix6d information(const IcpResult& icp) const;
  const TrackingConfig& config() const { return cfg_; }

 private:
  /// What the checks of one register_to() share: the RANSAC model's own checks and the pyramids.
  struct Evidence {
    const RansacResult* ransac = nullptr;
    bool trusted = false;  ///< enough inliers, spread and unambiguous
    RegistrationCheck feature_check;  ///< spread and second-model results
    const std::vector<DepthLevel>* frame_pyramid = nullptr;
    const std::vector<DepthLevel>* kf_pyramid = nullptr;
  };
  RegistrationCheck check_features(const FrameFeatures& frame_features, const std::vector<std::pair<int, int>>& pairs,
                                   const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                                   const RansacResult& ransac) const;
  void verify(OdometryResult& reg, const Evidence& evidence) const;
  void check_conditioning(OdometryResult& reg, const Evidence& evidence) const;
  void judge(OdometryResult& reg, const Evidence& evidence, const Pose* prior) const;
  IcpParams wide_params(double expected_error_m) const;

  TrackingConfig cfg_;
  PinholeIntrinsics intr_;
  cv::Ptr<cv::ORB> orb_, wide_orb_;
  IcpParams icp_params_, wide_icp_params_;
};

}  // namespace semap
