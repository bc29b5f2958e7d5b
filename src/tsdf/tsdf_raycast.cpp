#include "tsdf/tsdf_raycast.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

#include "tsdf/tsdf_interpolation.hpp"

namespace semap {

namespace {

/// Ray parameter (metres along the unit ray from `origin`) of the sdf's zero crossing nearest
/// `t0`, or a negative value when there is none within `reach` of it.
float zero_crossing(CachedVoxelLookup& lookup, const Eigen::Vector3f& origin, const Eigen::Vector3f& ray, float t0,
                    float reach, float step) {
  constexpr int kSecantSteps = 6;
  float t_a = t0, s_a;
  if (!interpolate_sdf(lookup, origin + t_a * ray, s_a)) return -1.0f;
  // Bracket: walk towards the surface (sdf > 0: in front of it, ahead along the ray) until the sign changes.
  const float dir = s_a > 0 ? 1.0f : -1.0f;
  float t_b = t_a, s_b = s_a;
  while (s_b * dir > 0) {
    t_a = t_b;
    s_a = s_b;
    t_b += dir * std::max(std::fabs(s_b), step);
    if (std::fabs(t_b - t0) > reach || !interpolate_sdf(lookup, origin + t_b * ray, s_b)) return -1.0f;
  }
  // A crossing from behind the surface to in front of it (negative to positive going forward)
  // is the back of a surface: not what the camera sees.
  if ((dir > 0 && !(s_a > 0 && s_b <= 0)) || (dir < 0 && !(s_b > 0 && s_a <= 0))) return -1.0f;
  for (int i = 0; i < kSecantSteps; ++i) {
    if (s_a == s_b) break;
    const float t = t_a - s_a * (t_b - t_a) / (s_b - s_a);
    float s;
    if (!interpolate_sdf(lookup, origin + t * ray, s)) break;
    if (std::fabs(s) < 1e-4f) return t;
    if ((s > 0) == (s_a > 0)) {
      t_a = t;
      s_a = s;
    } else {
      t_b = t;
      s_b = s;
    }
  }
  return s_a == s_b ? t_a : t_a - s_a * (t_b - t_a) / (s_b - s_a);
}

}  // namespace

cv::Mat surface_depth_along_rays(const TsdfMap& map, const cv::Mat& depth_m, const PinholeIntrinsics& k,
                                 const Pose& T_world_camera) {
  CV_Assert(depth_m.type() == CV_32FC1);
  cv::Mat out(depth_m.size(), CV_32FC1, cv::Scalar(0));
  const Eigen::Matrix3f R = T_world_camera.linear().cast<float>();
  const Eigen::Vector3f origin = T_world_camera.translation().cast<float>();
  const float reach = float(map.config().truncation());
  const float step = 0.5f * map.voxel_size();
  tbb::parallel_for(tbb::blocked_range<int>(0, depth_m.rows, 16), [&](const tbb::blocked_range<int>& rows) {
    CachedVoxelLookup lookup(map);
    for (int y = rows.begin(); y < rows.end(); ++y) {
      const float* z = depth_m.ptr<float>(y);
      float* o = out.ptr<float>(y);
      for (int x = 0; x < depth_m.cols; ++x) {
        if (!(z[x] > 0)) continue;
        const Eigen::Vector3f c((x - float(k.cx)) / float(k.fx), (y - float(k.cy)) / float(k.fy), 1.0f);
        const float norm = c.norm();  // depth z = t / norm along the unit ray
        const float t = zero_crossing(lookup, origin, R * (c / norm), z[x] * norm, reach, step);
        if (t > 0) o[x] = t / norm;
      }
    }
  });
  return out;
}

}  // namespace semap
