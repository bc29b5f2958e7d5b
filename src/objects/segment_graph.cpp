#include "objects/segment_graph.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>

namespace semap {

float semantic_weight(int mask_i, int mask_j, float w_diff, float w_bg) {
  if (mask_i == 0 || mask_j == 0) return w_bg;
  return mask_i == mask_j ? 0.f : w_diff;
}

bool generally_convex(const Eigen::Vector3f& c_i, const Eigen::Vector3f& n_i, const Eigen::Vector3f& c_j,
                      const Eigen::Vector3f& n_j) {
  return (n_i - n_j).dot(c_i - c_j) > 0.f;
}

bool passes_sanity_criterion(const Eigen::Vector3f& c_i, const Eigen::Vector3f& n_i, const Eigen::Vector3f& c_j,
                             const Eigen::Vector3f& n_j, float min_angle_deg) {
  const Eigen::Vector3f s = n_i.cross(n_j);
  const Eigen::Vector3f d = c_i - c_j;
  const float s_norm = s.norm(), d_norm = d.norm();
  if (s_norm < 1e-3f || d_norm < 1e-9f) return true;
  // Angle between d and the line along s, in [0, 90] deg (LCCP uses min(angle(d,s), angle(d,-s))).
  const float cos_angle = std::min(1.f, std::abs(d.dot(s)) / (s_norm * d_norm));
  const float angle_deg = std::acos(cos_angle) * 180.f / static_cast<float>(M_PI);
  return angle_deg >= min_angle_deg;
}

std::vector<bool> truly_convex_edges(const SupervoxelGraph& graph, float sanity_angle_deg) {
  const size_t n = graph.nodes.size();
  std::vector<std::vector<int>> neighbours(n);
  for (const auto& [a, b] : graph.edges) {
    neighbours[a].push_back(b);
    neighbours[b].push_back(a);
  }
  for (auto& list : neighbours) std::sort(list.begin(), list.end());
  auto convex = [&](int i, int j) {
    return generally_convex(graph.nodes[i].centroid, graph.nodes[i].normal, graph.nodes[j].centroid,
                            graph.nodes[j].normal);
  };
  std::vector<bool> result(graph.edges.size(), false);
  for (size_t e = 0; e < graph.edges.size(); ++e) {
    const auto [i, j] = graph.edges[e];
    const auto& ni = graph.nodes[i];
    const auto& nj = graph.nodes[j];
    if (!convex(i, j) || !passes_sanity_criterion(ni.centroid, ni.normal, nj.centroid, nj.normal, sanity_angle_deg))
      continue;
    // Common neighbour k generally convex with both (C2.4 a).
    std::vector<int> common;
    std::set_intersection(neighbours[i].begin(), neighbours[i].end(), neighbours[j].begin(), neighbours[j].end(),
                          std::back_inserter(common));
    for (int k : common) {
      if (convex(i, k) && convex(j, k)) {
        result[e] = true;
        break;
      }
    }
  }
  return result;
}

float geometric_weight(int plane_i, int plane_j, const Eigen::Vector3f& n_i, const Eigen::Vector3f& n_j,
                       bool convex) {
  if (plane_i == plane_j) return 0.f;
  if (plane_i == 0 || plane_j == 0) return 1.f;
  const float one_minus_dot = 1.f - std::clamp(n_i.dot(n_j), -1.f, 1.f);
  return convex ? 0.25f * one_minus_dot * one_minus_dot : one_minus_dot;
}

std::vector<int> assign_support_planes(const SupervoxelGraph& graph, const SupportPlaneParams& params) {
  const int n = static_cast<int>(graph.nodes.size());
  std::vector<std::vector<int>> neighbours(n);
  for (const auto& [a, b] : graph.edges) {
    neighbours[a].push_back(b);
    neighbours[b].push_back(a);
  }
  const float cos_max = std::cos(params.max_angle_deg * static_cast<float>(M_PI) / 180.f);
  std::vector<int> order;
  for (int i = 0; i < n; ++i)
    if (graph.nodes[i].curvature <= params.max_curvature) order.push_back(i);
  // Flattest seeds first, so a plane grows from its most reliable supervoxel.
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return graph.nodes[a].curvature < graph.nodes[b].curvature; });
  std::vector<int> region(n, -1);
  std::vector<int> labels(n, 0);
  int next_label = 1;
  int region_id = 0;
  for (int seed : order) {
    if (region[seed] >= 0) continue;
    const Eigen::Vector3f normal = graph.nodes[seed].normal;
    const Eigen::Vector3f origin = graph.nodes[seed].centroid;
    std::vector<int> members{seed};
    region[seed] = region_id;
    std::queue<int> frontier;
    frontier.push(seed);
    while (!frontier.empty()) {
      const int cur = frontier.front();
      frontier.pop();
      for (int nb : neighbours[cur]) {
        if (region[nb] >= 0) continue;
        const auto& node = graph.nodes[nb];
        if (node.curvature > params.max_curvature) continue;
        if (std::abs(node.normal.dot(normal)) < cos_max) continue;
        if (std::abs(normal.dot(node.centroid - origin)) > params.max_distance) continue;
        region[nb] = region_id;
        members.push_back(nb);
        frontier.push(nb);
      }
    }
    ++region_id;
    if (static_cast<int>(members.size()) < params.min_supervoxels) continue;
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e9f), hi = -lo;
    for (int m : members) {
      lo = lo.cwiseMin(graph.nodes[m].centroid);
      hi = hi.cwiseMax(graph.nodes[m].centroid);
    }
    if ((hi - lo).norm() < params.min_extent) continue;
    for (int m : members) labels[m] = next_label;
    ++next_label;
  }
  return labels;
}

double js_divergence(const std::vector<double>& p, const std::vector<double>& q) {
  double js = 0.0;
  const size_t n = std::min(p.size(), q.size());
  for (size_t k = 0; k < n; ++k) {
    const double m = 0.5 * (p[k] + q[k]);
    if (p[k] > 0) js += 0.5 * p[k] * std::log(p[k] / m);
    if (q[k] > 0) js += 0.5 * q[k] * std::log(q[k] / m);
  }
  return std::max(0.0, js);
}

std::vector<double> augmented_mean_scores(const std::vector<double>& score_sum, int n) {
  std::vector<double> out(score_sum.size() + 1, 0.0);
  if (n <= 0) {
    out[0] = 1.0;
    return out;
  }
  double total = 0.0;
  for (size_t k = 0; k < score_sum.size(); ++k) {
    out[k + 1] = std::max(0.0, score_sum[k] / n);
    total += out[k + 1];
  }
  out[0] = std::max(0.0, 1.0 - total);
  // Renormalise when the scores over-sum (e.g. unnormalised detector outputs).
  if (total > 1.0)
    for (auto& v : out) v /= total;
  return out;
}

}  // namespace semap
