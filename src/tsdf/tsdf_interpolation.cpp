#include "tsdf/tsdf_interpolation.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace semap {

bool interpolate_sdf(CachedVoxelLookup& lookup, const Eigen::Vector3f& q, float& sdf, Eigen::Vector3f* gradient) {
  const float s = lookup.map().voxel_size();
  const Eigen::Vector3f g = q / s - Eigen::Vector3f::Constant(0.5f);  // in voxel-centre units
  const Eigen::Vector3f base = g.array().floor();
  const Eigen::Vector3f t = g - base;
  const VoxelIndex b = base.cast<int>();
  float d[8];
  for (int corner = 0; corner < 8; ++corner) {
    const TsdfVoxel* voxel = lookup.observed(b + VoxelIndex(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1));
    if (!voxel) return false;
    d[corner] = voxel->sdf();
  }
  // Trilinear: along x, then y, then z.
  const float x00 = d[0] + t.x() * (d[1] - d[0]), x10 = d[2] + t.x() * (d[3] - d[2]);
  const float x01 = d[4] + t.x() * (d[5] - d[4]), x11 = d[6] + t.x() * (d[7] - d[6]);
  const float y0 = x00 + t.y() * (x10 - x00), y1 = x01 + t.y() * (x11 - x01);
  sdf = y0 + t.z() * (y1 - y0);
  if (gradient) {
    auto lerp2 = [&](float a, float b, float c, float e, float u, float v) {  // bilinear over the other two axes
      return (1 - u) * (1 - v) * a + u * (1 - v) * b + (1 - u) * v * c + u * v * e;
    };
    const float dx = lerp2(d[1] - d[0], d[3] - d[2], d[5] - d[4], d[7] - d[6], t.y(), t.z());
    const float dy = lerp2(d[2] - d[0], d[3] - d[1], d[6] - d[4], d[7] - d[5], t.x(), t.z());
    const float dz = lerp2(d[4] - d[0], d[5] - d[1], d[6] - d[2], d[7] - d[3], t.x(), t.y());
    *gradient = Eigen::Vector3f(dx, dy, dz) / s;
  }
  return true;
}

namespace {

Eigen::Vector3f projected(CachedVoxelLookup& lookup, const Eigen::Vector3f& p, float max_move, float keep_within) {
  constexpr int kSteps = 3;
  Eigen::Vector3f q = p;
  for (int step = 0; step < kSteps; ++step) {
    float sdf;
    Eigen::Vector3f gradient;
    if (!interpolate_sdf(lookup, q, sdf, &gradient)) return p;
    // A point already this close to the fused surface is as good as the TSDF's own estimate of
    // it (its discretisation error): only points the depth noise put farther off are moved.
    if (step == 0 && std::fabs(sdf) <= keep_within) return p;
    const float norm = gradient.norm();
    if (!(norm > 1e-3f)) return p;
    q -= (sdf / norm) * (gradient / norm);
    if ((q - p).norm() > max_move) return p;
  }
  return q;
}

}  // namespace

std::vector<Eigen::Vector3f> project_onto_surface(const TsdfMap& map, const std::vector<Eigen::Vector3f>& points) {
  std::vector<Eigen::Vector3f> out(points.size());
  const float max_move = static_cast<float>(map.config().truncation());
  const float keep_within = 0.25f * map.voxel_size();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    CachedVoxelLookup lookup(map);
    for (size_t i = r.begin(); i < r.end(); ++i) out[i] = projected(lookup, points[i], max_move, keep_within);
  });
  return out;
}

}  // namespace semap
