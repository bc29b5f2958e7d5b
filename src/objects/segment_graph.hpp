#pragma once
// The supervoxel adjacency graph of one frame and the pure pieces of METHODS.md C2.3-C2.5:
// support planes, LCCP convexity, edge weights and Felzenszwalb-Huttenlocher clustering.
// No PCL here (supervoxel_graph.cpp builds the graph with PCL's VCCS).
#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/graph_segmentation.hpp"  // WeightedEdge, felzenszwalb_cluster (C2.5)

namespace semap {

struct SupervoxelNode {
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();  ///< unit, oriented towards the camera
  float curvature = 0.f;
  std::vector<int> point_indices;  ///< into the frame cloud the graph was built from
  int mask = 0;         ///< m_i: the mask covering most of its points (0 = background), C2.3
  int centre_mask = 0;  ///< the mask at its centre's pixel, C2.6
  int plane = 0;        ///< l_i: support plane label, 0 = none, C2.4
};

struct SupervoxelGraph {
  std::vector<SupervoxelNode> nodes;
  std::vector<std::pair<int, int>> edges;  ///< adjacency, each pair once with first < second
};

struct SupportPlaneParams {
  float max_curvature = 0.04f;
  float max_angle_deg = 10.f;
  float max_distance = 0.02f;
  int min_supervoxels = 4;
  float min_extent = 0.3f;
};

/// omega_sem (C2.3): 0 when both in the same non-zero mask, w_diff for two different masks,
/// w_bg when either is background.
float semantic_weight(int mask_i, int mask_j, float w_diff, float w_bg);

/// LCCP "generally convex" (C2.4): (n_i - n_j) . (c_i - c_j) > 0.
bool generally_convex(const Eigen::Vector3f& c_i, const Eigen::Vector3f& n_i, const Eigen::Vector3f& c_j,
                      const Eigen::Vector3f& n_j);

/// LCCP sanity criterion: angle between c_i - c_j and n_i x n_j at least `min_angle_deg`
/// (close enough to 90 deg). Nearly parallel normals pass (the cross product is undefined).
bool passes_sanity_criterion(const Eigen::Vector3f& c_i, const Eigen::Vector3f& n_i, const Eigen::Vector3f& c_j,
                             const Eigen::Vector3f& n_j, float min_angle_deg);

/// Truly convex per edge of `graph` (C2.4): generally convex, a common neighbour generally
/// convex with both, and the sanity criterion.
std::vector<bool> truly_convex_edges(const SupervoxelGraph& graph, float sanity_angle_deg);

/// omega_geo (C2.4), as printed: 0 on the same plane label (both 0 included), 1 when exactly
/// one is 0, 1/4 (1 - n_i.n_j)^2 for different planes and convex, 1 - n_i.n_j when concave.
float geometric_weight(int plane_i, int plane_j, const Eigen::Vector3f& n_i, const Eigen::Vector3f& n_j,
                       bool convex);

/// Support planes (C2.4): region growing over adjacent low-curvature supervoxels with similar
/// normals lying on one plane. Returns l_i per node (1-based, 0 = none).
std::vector<int> assign_support_planes(const SupervoxelGraph& graph, const SupportPlaneParams& params);

/// Jensen-Shannon divergence in nats (C5); inputs are distributions of equal size.
double js_divergence(const std::vector<double>& p, const std::vector<double>& q);

/// Augmented mean score vector (C5): (1 - sum_k c_k / n, c_1 / n, ..., c_C / n), clamped >= 0.
std::vector<double> augmented_mean_scores(const std::vector<double>& score_sum, int n);

}  // namespace semap
