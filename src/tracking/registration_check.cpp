#include "tracking/registration_check.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace semap {

namespace {
constexpr int kNeighbourhood[9][2] = {{0, 0}, {-1, 0}, {1, 0}, {0, -1}, {0, 1}, {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
}  // namespace

double depth_noise_sigma(double z_m, const VerificationParams& p) { return p.depth_noise.sigma_m(z_m); }

DenseResidual dense_depth_residual(const DepthLevel& frame, const DepthLevel& reference, const Pose& T_ref_frame,
                                   const VerificationParams& params) {
  DenseResidual out;
  const Eigen::Matrix3f R = T_ref_frame.linear().cast<float>();
  const Eigen::Vector3f t = T_ref_frame.translation().cast<float>();
  const PinholeIntrinsics& K = reference.intrinsics;
  const cv::Mat& ref = reference.vertices;
  for (int v = 0; v < frame.vertices.rows; ++v) {
    const cv::Vec3f* row = frame.vertices.ptr<cv::Vec3f>(v);
    for (int u = 0; u < frame.vertices.cols; ++u) {
      const cv::Vec3f& p = row[u];
      if (!std::isfinite(p[2])) continue;
      ++out.valid;
      const Eigen::Vector3f q = R * Eigen::Vector3f(p[0], p[1], p[2]) + t;
      if (q.z() <= 0) continue;
      const int ur = int(std::lround(K.fx * q.x() / q.z() + K.cx));
      const int vr = int(std::lround(K.fy * q.y() / q.z() + K.cy));
      if (ur < 0 || vr < 0 || ur >= ref.cols || vr >= ref.rows) continue;
      // 3x3 neighbourhood: a one-pixel misregistration at a depth edge is not evidence.
      const double bound = params.residual_sigmas * depth_noise_sigma(q.z(), params) + params.residual_pose_tolerance_m;
      bool seen = false, agrees = false, in_front_all = true;
      for (int i = 0; i < 9 && !agrees; ++i) {
        const int x = ur + kNeighbourhood[i][0], y = vr + kNeighbourhood[i][1];  // the centre first
        if (x < 0 || y < 0 || x >= ref.cols || y >= ref.rows) continue;
        const float z_ref = ref.at<cv::Vec3f>(y, x)[2];
        if (!std::isfinite(z_ref)) continue;
        seen = true;
        const double in_front = z_ref - q.z();  // > 0: between the reference camera and its surface
        agrees = std::abs(in_front) <= bound;
        in_front_all = in_front_all && in_front > bound;
      }
      if (!seen) continue;
      ++out.overlap;
      if (agrees) ++out.agreeing;
      else if (in_front_all) ++out.violating;
    }
  }
  return out;
}

int occupied_grid_cells(const std::vector<cv::Point2f>& points, int width, int height, int grid) {
  if (width <= 0 || height <= 0 || grid <= 0) return 0;
  std::vector<char> occupied(size_t(grid * grid), 0);
  for (const auto& pt : points) {
    const int cx = std::clamp(int(pt.x * grid / width), 0, grid - 1);
    const int cy = std::clamp(int(pt.y * grid / height), 0, grid - 1);
    occupied[size_t(cy * grid + cx)] = 1;
  }
  return int(std::count(occupied.begin(), occupied.end(), 1));
}

int ransac_runner_up(const RansacResult& ransac, const std::vector<Eigen::Vector3d>& src,
                     const std::vector<Eigen::Vector3d>& dst, double inlier_distance_m, int min_votes) {
  const double max_sq = inlier_distance_m * inlier_distance_m;
  int runner_up = 0;
  for (const auto& [votes, T] : ransac.hypotheses) {
    if (votes <= runner_up || votes < min_votes) continue;
    int shared = 0;  // the model's votes from the result's inliers
    for (int i : ransac.inliers) shared += (T * src[size_t(i)] - dst[size_t(i)]).squaredNorm() < max_sq;
    if (2 * shared < votes) runner_up = votes;
  }
  return runner_up;
}

Matrix6d point_to_plane_information(const DepthLevel& level) {
  Matrix6d H = Matrix6d::Zero();
  if (level.normals.empty()) return H;
  for (int v = 0; v < level.vertices.rows; ++v) {
    const cv::Vec3f* pv = level.vertices.ptr<cv::Vec3f>(v);
    const cv::Vec3f* nv = level.normals.ptr<cv::Vec3f>(v);
    for (int u = 0; u < level.vertices.cols; ++u) {
      if (!std::isfinite(pv[u][2]) || !std::isfinite(nv[u][2])) continue;
      const Eigen::Vector3d p(pv[u][0], pv[u][1], pv[u][2]), n(nv[u][0], nv[u][1], nv[u][2]);
      Vector6d J;
      J << p.cross(n), n;
      H.noalias() += J * J.transpose();
    }
  }
  return H;
}

double scaled_min_information_eigenvalue(const Matrix6d& hessian) {
  const double tr_rot = hessian.topLeftCorner<3, 3>().trace();
  const double tr_trans = hessian.bottomRightCorner<3, 3>().trace();
  if (!(tr_trans > 0) || !(tr_rot > 0)) return 0.0;
  // Rotation in radians x lever = metres of point motion: both blocks then have the trace tr_trans.
  Vector6d scale;
  scale.head<3>().setConstant(std::sqrt(tr_trans / tr_rot));
  scale.tail<3>().setOnes();
  const Matrix6d scaled = scale.asDiagonal() * hessian * scale.asDiagonal() / tr_trans;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(scaled, Eigen::EigenvaluesOnly);
  return std::max(0.0, eig.eigenvalues()(0));
}

}  // namespace semap
