#pragma once
// Keyframe pose graph optimised with Ceres (METHODS.md A4).
#include <map>
#include <vector>

#include "semap/core/pose.hpp"
#include "tracking/registration.hpp"

namespace semap {

struct PoseGraphEdge {
  int from = 0, to = 0;           ///< vertex ids
  Pose T_from_to = Pose::Identity();  ///< measured relative pose
  /// Information of the measurement, order (rotation, translation), for the right perturbation
  /// T_from_to * exp(delta) (see information_from_icp).
  Matrix6d information = Matrix6d::Identity();
  bool is_loop = false;           ///< loop edges get a robust (Huber) loss
};

class PoseGraph {
 public:
  /// Adds (or replaces the initial value of) vertex `id` with pose T_world_vertex.
  void add_vertex(int id, const Pose& T_world_vertex);
  void add_edge(const PoseGraphEdge& edge);
  bool has_vertex(int id) const { return vertices_.count(id) > 0; }
  /// Optimises all vertices except the smallest id (fixed gauge) and those below
  /// set_fixed_below(). Returns false when Ceres reports failure (poses are then left unchanged).
  bool optimize(int max_iterations, double loop_huber_scale);
  /// Vertices with an id below `id` stay fixed (a resumed map's keyframes, issue 19).
  void set_fixed_below(int id) { fixed_below_ = id; }
  const std::map<int, Pose>& vertices() const { return vertices_; }
  Pose pose(int id) const { return vertices_.at(id); }
  const std::vector<PoseGraphEdge>& edges() const { return edges_; }
  size_t loop_edge_count() const;
  /// Sum of squared whitened residuals at the current vertex poses.
  double total_error() const;

 private:
  std::map<int, Pose> vertices_;
  std::vector<PoseGraphEdge> edges_;
  int fixed_below_ = 0;
};

/// Converts an ICP Hessian (left perturbation exp(xi) * T in the target frame, order rotation,
/// translation, unit residuals) into edge information for the right perturbation T * exp(delta):
/// info = A^-T (H / sigma^2 * effective / matched) A^-1 with delta = A xi.
Matrix6d information_from_icp(const Matrix6d& hessian, const Pose& T_target_source, int matched, double sigma,
                              double effective_points);

}  // namespace semap
