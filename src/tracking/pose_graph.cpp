#include "tracking/pose_graph.hpp"

#include <ceres/ceres.h>
#include <ceres/manifold.h>

#include <Eigen/Cholesky>

namespace semap {

namespace {
Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// Residual = sqrt_info * [2 vec(q_d); t_d] with T_d = T_meas^-1 * T_i^-1 * T_j.
struct RelativePoseError {
  RelativePoseError(const Pose& measured, const Matrix6d& sqrt_information)
      : q_meas_inv(Eigen::Quaterniond(measured.linear()).conjugate()),
        t_meas(measured.translation()),
        sqrt_info(sqrt_information) {}

  template <typename T>
  bool operator()(const T* qi_raw, const T* ti_raw, const T* qj_raw, const T* tj_raw, T* residual_raw) const {
    Eigen::Map<const Eigen::Quaternion<T>> qi(qi_raw), qj(qj_raw);
    Eigen::Map<const Eigen::Matrix<T, 3, 1>> ti(ti_raw), tj(tj_raw);
    const Eigen::Quaternion<T> qi_inv = qi.conjugate();
    const Eigen::Quaternion<T> q_ij = qi_inv * qj;
    const Eigen::Matrix<T, 3, 1> t_ij = qi_inv * (tj - ti);
    const Eigen::Quaternion<T> q_meas_inv_t = q_meas_inv.template cast<T>();
    const Eigen::Quaternion<T> q_d = q_meas_inv_t * q_ij;
    const Eigen::Matrix<T, 3, 1> t_d = q_meas_inv_t * (t_ij - t_meas.template cast<T>());
    Eigen::Matrix<T, 6, 1> r;
    // Sign of w: keep the short way round.
    const T sign = q_d.w() < T(0) ? T(-1) : T(1);
    r.template head<3>() = T(2) * sign * q_d.vec();
    r.template tail<3>() = t_d;
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residual(residual_raw);
    residual = sqrt_info.template cast<T>() * r;
    return true;
  }

  Eigen::Quaterniond q_meas_inv;
  Eigen::Vector3d t_meas;
  Matrix6d sqrt_info;
};
}  // namespace

void PoseGraph::add_vertex(int id, const Pose& T_world_vertex) { vertices_[id] = T_world_vertex; }

void PoseGraph::add_edge(const PoseGraphEdge& edge) { edges_.push_back(edge); }

size_t PoseGraph::loop_edge_count() const {
  size_t n = 0;
  for (const auto& e : edges_) n += e.is_loop;
  return n;
}

static Matrix6d sqrt_information(const Matrix6d& info) {
  Eigen::LLT<Matrix6d> llt(0.5 * (info + info.transpose()));
  if (llt.info() != Eigen::Success) return Matrix6d::Identity();
  return llt.matrixU();  // U^T U = info
}

double PoseGraph::total_error() const {
  double sum = 0.0;
  for (const auto& e : edges_) {
    if (!vertices_.count(e.from) || !vertices_.count(e.to)) continue;
    const Pose& a = vertices_.at(e.from);
    const Pose& b = vertices_.at(e.to);
    RelativePoseError err(e.T_from_to, sqrt_information(e.information));
    Eigen::Quaterniond qa(a.linear()), qb(b.linear());
    Eigen::Vector3d ta = a.translation(), tb = b.translation();
    double r[6];
    err(qa.coeffs().data(), ta.data(), qb.coeffs().data(), tb.data(), r);
    for (double v : r) sum += v * v;
  }
  return sum;
}

bool PoseGraph::optimize(int max_iterations, double loop_huber_scale) {
  if (vertices_.size() < 2 || edges_.empty()) return true;
  std::map<int, Eigen::Quaterniond> quats;
  std::map<int, Eigen::Vector3d> trans;
  for (const auto& [id, pose] : vertices_) {
    quats[id] = Eigen::Quaterniond(pose.linear()).normalized();
    trans[id] = pose.translation();
  }
  ceres::Problem problem;
  for (const auto& e : edges_) {
    if (!vertices_.count(e.from) || !vertices_.count(e.to) || e.from == e.to) continue;
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseError, 6, 4, 3, 4, 3>(
        new RelativePoseError(e.T_from_to, sqrt_information(e.information)));
    ceres::LossFunction* loss = e.is_loop && loop_huber_scale > 0 ? new ceres::HuberLoss(loop_huber_scale) : nullptr;
    problem.AddResidualBlock(cost, loss, quats[e.from].coeffs().data(), trans[e.from].data(),
                             quats[e.to].coeffs().data(), trans[e.to].data());
  }
  const int fixed = vertices_.begin()->first;
  for (auto& [id, q] : quats) {
    if (!problem.HasParameterBlock(q.coeffs().data())) continue;
    problem.SetManifold(q.coeffs().data(), new ceres::EigenQuaternionManifold);
    if (id == fixed || id < fixed_below_) {
      problem.SetParameterBlockConstant(q.coeffs().data());
      problem.SetParameterBlockConstant(trans[id].data());
    }
  }
  ceres::Solver::Options options;
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;
  options.linear_solver_type =
      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ||
              ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE)
          ? ceres::SPARSE_NORMAL_CHOLESKY
          : ceres::DENSE_QR;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable()) return false;
  for (auto& [id, pose] : vertices_) {
    Pose p = Pose::Identity();
    p.linear() = quats[id].normalized().toRotationMatrix();
    p.translation() = trans[id];
    pose = p;
  }
  return true;
}

Matrix6d information_from_icp(const Matrix6d& hessian, const Pose& T, int matched, double sigma,
                              double effective_points) {
  if (matched <= 0 || !hessian.allFinite()) return Matrix6d::Identity();
  const Eigen::Matrix3d rt = T.linear().transpose();
  // delta = A xi: rotation R^T w, translation R^T (v - t x w) (see header).
  Matrix6d a = Matrix6d::Zero();
  a.topLeftCorner<3, 3>() = rt;
  a.bottomLeftCorner<3, 3>() = -rt * skew(T.translation());
  a.bottomRightCorner<3, 3>() = rt;
  const Matrix6d a_inv = a.inverse();
  const double scale = std::min(1.0, effective_points / matched) / (sigma * sigma);
  Matrix6d info = a_inv.transpose() * (hessian * scale) * a_inv;
  info = 0.5 * (info + info.transpose());
  // Keep it positive definite for the LLT (planar scenes leave directions unconstrained).
  info.diagonal().array() += 1e-6 * std::max(1.0, info.diagonal().maxCoeff());
  return info;
}

}  // namespace semap
