#pragma once
// Registration building blocks of the odometry (METHODS.md A2): closed-form rigid fit
// (Kabsch/Umeyama), voting RANSAC over 3D-3D matches, ORB features with 3D points, and
// coarse-to-fine point-to-plane ICP with projective data association.
#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/pose.hpp"
#include "semap/tracking/tracking_config.hpp"  // IcpParams, RansacParams

namespace semap {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Least-squares rigid transform T with dst_i ~ T * src_i (Kabsch/Umeyama, no scale).
/// Needs >= 3 non-collinear pairs; returns identity (and ok=false) otherwise.
Pose fit_rigid(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst, bool* ok = nullptr);

struct RansacResult {
  bool ok = false;                 ///< >= min_inliers after the refit
  Pose T = Pose::Identity();       ///< dst ~ T * src
  std::vector<int> inliers;        ///< indices into the pairs
  double inlier_rmse = 0.0;        ///< metres
  int best_votes = 0;              ///< votes of the best sampled model (before the refit)
  /// Every sampled model with at least min_inliers votes (votes, model): the second hypotheses
  /// a match is checked against (issue 42, registration_check.hpp ransac_runner_up).
  std::vector<std::pair<int, Pose>> hypotheses;
};
/// Voting RANSAC (METHODS.md A2 step 3): 3-pair samples, Kabsch, inlier votes under a distance
/// threshold, best hypothesis refit on all its inliers (twice). Deterministic for a seed.
RansacResult ransac_rigid(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                          const RansacParams& params);

/// ORB keypoints of one image with their back-projected 3D points (camera frame).
struct FrameFeatures {
  std::vector<cv::KeyPoint> keypoints;  ///< only keypoints with valid depth are kept
  cv::Mat descriptors;                  ///< CV_8U, one row per keypoint
  std::vector<Eigen::Vector3d> points;  ///< camera-frame points, metres
};
/// ORB on `gray` (CV_8UC1); keeps keypoints whose depth (CV_32FC1, metres) is in range.
FrameFeatures extract_features(cv::ORB& orb, const cv::Mat& gray, const cv::Mat& depth,
                               const PinholeIntrinsics& intrinsics, double min_depth, double max_depth);
/// Brute-force Hamming matching query->train with ratio test and a mutual (cross) check.
/// Returns (query index, train index) pairs.
std::vector<std::pair<int, int>> match_features(const FrameFeatures& query, const FrameFeatures& train,
                                                double ratio, int max_hamming);

/// One level of an RGB-D pyramid: vertex and normal maps in the camera frame, and optionally
/// the intensity image with its gradients (for the photometric term of the ICP).
struct DepthLevel {
  PinholeIntrinsics intrinsics;
  cv::Mat vertices;   ///< CV_32FC3, NaN where invalid
  cv::Mat normals;    ///< CV_32FC3, NaN where invalid (empty when not requested / not needed)
  cv::Mat intensity;  ///< CV_32FC1 in [0, 1], empty unless a grey image was given
  /// CV_32FC3 (I, dI/dx, dI/dy) per pixel (central differences), the target side of the
  /// photometric term packed for one bilinear fetch; empty in a source-only pyramid.
  cv::Mat intensity_gradients;
};
/// Coarse-to-fine depth pyramid (level 0 = input). Depth outside [min, max] is invalid;
/// downsampling averages the valid pixels of each 2x2 block that agree with its first valid one.
/// With `gray` (CV_8UC1, the depth's size, registered) every level also gets the intensity,
/// blurred lightly (Gaussian sigma 1 px, against motion blur and noise) and area-downsampled
/// like the depth, with its gradients.
/// `source_only`: only what the ICP reads from its source (vertices, intensity, the normals of
/// the normal gate at coarse levels); complete_target_pyramid() adds the rest if the frame
/// later becomes a target (keyframe). Saves the per-frame cost (METHODS.md A2 step 4).
std::vector<DepthLevel> build_depth_pyramid(const cv::Mat& depth, const PinholeIntrinsics& intrinsics, int levels,
                                            double min_depth, double max_depth, bool with_normals,
                                            const cv::Mat& gray = cv::Mat(), bool source_only = false);
/// Adds the target-side data a source-only pyramid lacks (normals at every level when
/// `with_normals`, intensity gradients). No-op on a full pyramid.
void complete_target_pyramid(std::vector<DepthLevel>& pyramid, bool with_normals);
/// Whether the ICP reads the source normals of this level (normal gate; the 1-pixel Kinect
/// normals at full resolution are too noisy to gate with).
inline bool icp_uses_source_normals(const DepthLevel& level) { return level.vertices.cols < 640; }

struct IcpResult {
  bool converged = false;
  Pose T_target_source = Pose::Identity();
  double rmse = 0.0;               ///< point-to-plane RMSE of the matched points at level 0, metres
  int matched = 0;                 ///< correspondences at level 0
  double overlap = 0.0;            ///< matched / valid source points at level 0
  int photometric_matched = 0;      ///< intensity residuals at level 0 (0 without the term)
  Matrix6d hessian = Matrix6d::Zero();  ///< geometric J^T J at the result, order (rotation, translation), left perturbation in the target frame
  int iterations_run = 0;
};
/// Point-to-plane ICP (METHODS.md A2 step 4): source vertices are transformed by the current
/// estimate, projected into the target image (projective association), matched to the target
/// vertex/normal there; Gauss-Newton with Huber weights, coarse to fine. Row-parallel.
/// With params.photometric_weight > 0 each projected point also contributes the intensity
/// residual I_target(pi(T p)) - I_source(p) (bilinear, gradient Jacobian): the texture then
/// constrains motions the geometry leaves weak (sliding along planes).
IcpResult icp_point_to_plane(const std::vector<DepthLevel>& source, const std::vector<DepthLevel>& target,
                             const Pose& initial_T_target_source, const IcpParams& params);

/// exp of a twist (rotation first, translation second) as an isometry (first-order SE(3)).
Pose twist_exp(const Vector6d& xi);

}  // namespace semap
