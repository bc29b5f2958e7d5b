#pragma once
// Internal to the integrators: Amanatides-Woo traversal of the cells a segment crosses and the
// packed voxel/block keys (grouped rays, projective truncation bands). Not installed.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include "tsdf/integrator_common.hpp"

namespace semap::integrator_detail {

/// floor(x) as a cell index: the truncating cast, one lower for negative non-integers. Equal
/// to std::floor within the int range, without its libm/SSE4.1-less slow path.
inline int32_t floor_cell(float x) {
  const int32_t t = static_cast<int32_t>(x);
  return t - (x < static_cast<float>(t) ? 1 : 0);
}
inline Eigen::Vector3i floor_cells(const Eigen::Vector3f& p) { return {floor_cell(p.x()), floor_cell(p.y()), floor_cell(p.z())}; }

/// Visits n cells from `cell`, each step along the axis of the smallest t_max (ties: as
/// x < y ? (x < z ? x : z) : (y < z ? y : z), i.e. x when x < y and x < z, else y when y < z,
/// else z). The axis is chosen by selects on values kept in registers: a data-dependent branch
/// mispredicts, and an indexed array update went through memory (store-forwarding latency on
/// every step of the loop-carried chain).
template <class Visit>
inline void step_cells(std::array<int, 3> cell, const std::array<int, 3>& step, std::array<float, 3> t_max,
                       const std::array<float, 3>& t_delta, int n, Visit&& visit) {
  int cx = cell[0], cy = cell[1], cz = cell[2];
  float tx = t_max[0], ty = t_max[1], tz = t_max[2];
  for (int i = 0; i < n; ++i) {
    visit(Eigen::Vector3i(cx, cy, cz));
    const bool sx = (tx < ty) & (tx < tz);
    const bool sy = !sx & (ty < tz);
    const bool sz = !sx & !sy;
    cx += sx ? step[0] : 0;
    cy += sy ? step[1] : 0;
    cz += sz ? step[2] : 0;
    tx = sx ? tx + t_delta[0] : tx;
    ty = sy ? ty + t_delta[1] : ty;
    tz = sz ? tz + t_delta[2] : tz;
  }
}

/// The stepping part of traverse_cells: the n cells from c = floor(pa) along pa -> pb.
template <class Visit>
void traverse_steps(const Eigen::Vector3f& pa, const Eigen::Vector3f& pb, const Eigen::Vector3i& c, int n, Visit&& visit) {
  const Eigen::Vector3f dir = pb - pa;
  std::array<int, 3> cell{c.x(), c.y(), c.z()}, step;
  alignas(16) std::array<float, 4> t_max, t_delta, num{0, 0, 0, 0}, den{1, 1, 1, 1}, sign{0, 0, 0, 0};
  for (int i = 0; i < 3; ++i) {
    step[i] = dir[i] > 0 ? 1 : (dir[i] < 0 ? -1 : 0);
    num[i] = static_cast<float>(c[i] + (step[i] > 0 ? 1 : 0)) - pa[i];  // to the first boundary
    den[i] = dir[i];
    sign[i] = static_cast<float>(step[i]);
  }
  // The six divisions as two 4-lane ones (the same IEEE quotients); axes without motion never step.
#ifdef SEMAP_TSDF_X86
  const __m128 d = _mm_load_ps(den.data());
  _mm_store_ps(t_max.data(), _mm_div_ps(_mm_load_ps(num.data()), d));
  _mm_store_ps(t_delta.data(), _mm_div_ps(_mm_load_ps(sign.data()), d));
#else
  for (int i = 0; i < 4; ++i) t_max[i] = num[i] / den[i], t_delta[i] = sign[i] / den[i];
#endif
  for (int i = 0; i < 3; ++i)
    if (step[i] == 0) t_max[i] = t_delta[i] = std::numeric_limits<float>::infinity();
  step_cells(cell, step, {t_max[0], t_max[1], t_max[2]}, {t_delta[0], t_delta[1], t_delta[2]}, n, visit);
}

/// Amanatides-Woo traversal of the unit cells crossed by segment pa -> pb (in cell units).
template <class Visit>
void traverse_cells(const Eigen::Vector3f& pa, const Eigen::Vector3f& pb, Visit&& visit) {
  Eigen::Vector3i c = floor_cells(pa);
  const Eigen::Vector3i end = floor_cells(pb);
  const int n = 1 + std::abs(end.x() - c.x()) + std::abs(end.y() - c.y()) + std::abs(end.z() - c.z());
  if (n <= 2) {  // the common short segment: its end cells are all it crosses, no stepping needed
    visit(c);
    if (n == 2) visit(end);
    return;
  }
  traverse_steps(pa, pb, c, n, visit);
}

// Group keys: 21 bits per axis (voxel indices within +-2^20).
constexpr int kKeyBits = 21;
constexpr int32_t kKeyOffset = 1 << (kKeyBits - 1);
/// Non-zero when a voxel index is outside the key range: each offset coordinate within
/// [0, 2^kKeyBits), as unsigned, one test for all three (an int, for vectorised loops).
inline uint32_t key_range_excess(int32_t x, int32_t y, int32_t z) {
  return (static_cast<uint32_t>(x + kKeyOffset) | static_cast<uint32_t>(y + kKeyOffset) | static_cast<uint32_t>(z + kKeyOffset)) >>
         kKeyBits;
}
inline bool key_in_range(const Eigen::Vector3i& v) { return key_range_excess(v.x(), v.y(), v.z()) == 0; }
inline uint64_t pack_key(const Eigen::Vector3i& v) {
  return static_cast<uint64_t>(v.x() + kKeyOffset) | (static_cast<uint64_t>(v.y() + kKeyOffset) << kKeyBits) |
         (static_cast<uint64_t>(v.z() + kKeyOffset) << (2 * kKeyBits));
}
inline size_t mix_key(uint64_t k) {
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdULL;
  k ^= k >> 33;
  return static_cast<size_t>(k);
}

}  // namespace semap::integrator_detail
