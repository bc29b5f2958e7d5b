// Object geometry for the scene graph (scene_graph.hpp): the vertical box, the main part and
// the support height of an object's points in the gravity frame.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <deque>
#include <unordered_map>

#include "semap/navigation/scene_graph.hpp"

namespace semap {
namespace {

// z extent of an object's box. Top: the 98th percentile (a stray point above does not lift the
// surface things rest on). Bottom: the k-th lowest point, k = max(5, n / 500): a percentile
// would climb up the thin legs of a table or chair, which hold few of its points.
constexpr double kBoxHighQuantile = 0.98;
constexpr size_t kBottomMinPoints = 5, kBottomPointsPer = 500;

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

struct VoxelKeyHash {
  size_t operator()(const Eigen::Vector3i& v) const {
    return static_cast<size_t>(v.x()) * 73856093u ^ static_cast<size_t>(v.y()) * 19349663u ^
           static_cast<size_t>(v.z()) * 83492791u;
  }
};

}  // namespace

bool GravityBox::footprint_contains(const Eigen::Vector2d& xy_G, double margin_m) const {
  const Eigen::Vector2d d = xy_G - center_G.head<2>();
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const Eigen::Vector2d local(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  return std::abs(local.x()) <= 0.5 * size_m.x() + margin_m && std::abs(local.y()) <= 0.5 * size_m.y() + margin_m;
}

bool GravityBox::contains(const Eigen::Vector3d& p_G) const {
  return footprint_contains(p_G.head<2>()) && p_G.z() >= bottom_m() && p_G.z() <= top_m();
}

GravityBox gravity_box(const std::vector<Eigen::Vector3d>& points_G) {
  GravityBox box;
  if (points_G.empty()) return box;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points_G) mean += p.head<2>();
  mean /= static_cast<double>(points_G.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const auto& p : points_G) scatter += (p.head<2>() - mean) * (p.head<2>() - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  const Eigen::Vector2d major = eig.eigenvectors().col(1);
  box.yaw_rad = std::atan2(major.y(), major.x());
  const double c = std::cos(box.yaw_rad), s = std::sin(box.yaw_rad);
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(1e18), hi = -lo;
  std::vector<double> z;
  z.reserve(points_G.size());
  for (const auto& p : points_G) {
    const Eigen::Vector2d local(c * p.x() + s * p.y(), -s * p.x() + c * p.y());
    lo = lo.cwiseMin(local), hi = hi.cwiseMax(local);
    z.push_back(p.z());
  }
  const size_t k = std::min(z.size() - 1, std::max(kBottomMinPoints, z.size() / kBottomPointsPer) - 1);
  std::nth_element(z.begin(), z.begin() + k, z.end());
  const double z_lo = z[k], z_hi = quantile(z, kBoxHighQuantile);
  const Eigen::Vector2d centre_local = 0.5 * (lo + hi);
  box.center_G = {c * centre_local.x() - s * centre_local.y(), s * centre_local.x() + c * centre_local.y(),
                  0.5 * (z_lo + z_hi)};
  box.size_m = {hi.x() - lo.x(), hi.y() - lo.y(), z_hi - z_lo};
  return box;
}

std::vector<Eigen::Vector3d> main_part(const std::vector<Eigen::Vector3d>& points_G) {
  // Points per occupied voxel, then connected voxel components by breadth-first search.
  std::unordered_map<Eigen::Vector3i, std::vector<size_t>, VoxelKeyHash> voxels;
  for (size_t i = 0; i < points_G.size(); ++i)
    if (points_G[i].allFinite()) voxels[(points_G[i] / kMainPartVoxelM).array().floor().cast<int>()].push_back(i);
  std::unordered_map<Eigen::Vector3i, int, VoxelKeyHash> component;
  std::vector<size_t> best;
  for (const auto& [seed, unused] : voxels) {
    if (component.count(seed)) continue;
    const int c = static_cast<int>(component.size());
    std::vector<size_t> members;
    std::deque<Eigen::Vector3i> queue{seed};
    component[seed] = c;
    while (!queue.empty()) {
      const Eigen::Vector3i v = queue.front();
      queue.pop_front();
      const std::vector<size_t>& here = voxels.at(v);
      members.insert(members.end(), here.begin(), here.end());
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const Eigen::Vector3i w = v + Eigen::Vector3i(dx, dy, dz);
            if (voxels.count(w) && !component.count(w)) component[w] = c, queue.push_back(w);
          }
    }
    if (members.size() > best.size()) best.swap(members);
  }
  std::sort(best.begin(), best.end());  // keep the input's order
  std::vector<Eigen::Vector3d> out;
  out.reserve(best.size());
  for (size_t i : best) out.push_back(points_G[i]);
  return out;
}

double support_height(const std::vector<Eigen::Vector3d>& points_G, const GravityBox& box) {
  const double lo = box.center_G.z(), hi = box.top_m() + kSupportBinM;
  if (points_G.empty() || !(hi > lo)) return box.top_m();
  const size_t bins = static_cast<size_t>((hi - lo) / kSupportBinM) + 1;
  std::vector<size_t> count(bins + 1, 0);
  for (const Eigen::Vector3d& p : points_G)
    if (p.z() >= lo && p.z() < hi) ++count[static_cast<size_t>((p.z() - lo) / kSupportBinM)];
  size_t best = 0;  // ties go to the higher layer (a solid block rests things on its top)
  for (size_t b = 1; b + 1 < count.size(); ++b)
    if (count[b] + count[b + 1] >= count[best] + count[best + 1]) best = b;
  const double z0 = lo + best * kSupportBinM, z1 = z0 + 2 * kSupportBinM;
  std::vector<double> layer;
  for (const Eigen::Vector3d& p : points_G)
    if (p.z() >= z0 && p.z() < z1) layer.push_back(p.z());
  return layer.empty() ? box.top_m() : quantile(layer, 0.5);
}

}  // namespace semap
