#include "synth/depth_noise.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

#include "semap/core/error.hpp"
#include "synth/random.hpp"

namespace semap {

void DepthNoiseParams::visit(ParamVisitor& v) {
  v.param("sigma_a", sigma_a, "m", "constant term of the axial noise sigma (Nguyen et al. 2012)");
  v.param("sigma_b", sigma_b, "1/m", "quadratic term: sigma = a + b (z - z0)^2");
  v.param("sigma_z0", sigma_z0, "m", "offset z0 of the quadratic term");
  v.param("min_range", min_range, "m", "closer depth is invalid (0)");
  v.param("max_range", max_range, "m", "farther depth is invalid (0)");
  v.param("grazing_angle_deg", grazing_angle_deg, "deg", "incidence angles beyond this give no depth");
  v.param("edge_jump", edge_jump, "m", "depth jump counted as an edge (plus edge_jump_per_m * z)");
  v.param("edge_jump_per_m", edge_jump_per_m, "m/m", "depth-proportional part of the edge jump");
  v.param("edge_band_px", edge_band_px, "px", "band beside a jump (far side) where depth goes missing");
  v.param("edge_dropout", edge_dropout, "", "probability that a band pixel is dropped");
  v.param("quantise_disparity", quantise_disparity, "", "quantise depth in disparity steps (structured light)");
  v.param("baseline", baseline, "m", "projector-camera baseline used for quantisation");
  v.param("disparity_step_px", disparity_step_px, "px", "disparity resolution (Kinect v1: 1/8 px)");
}

double depth_noise_sigma(const DepthNoiseParams& p, double z) {
  const double dz = z - p.sigma_z0;
  return p.sigma_a + p.sigma_b * dz * dz;
}

cv::Mat apply_depth_noise(const cv::Mat& depth, const cv::Mat& cos_incidence, double fx, uint64_t seed,
                          const DepthNoiseParams& p) {
  if (depth.type() != CV_32FC1) throw Error("synth depth noise", "depth must be CV_32FC1");
  if (!cos_incidence.empty() && (cos_incidence.type() != CV_32FC1 || cos_incidence.size() != depth.size()))
    throw Error("synth depth noise", "cos_incidence must be CV_32FC1 of the depth size");
  cv::Mat out(depth.size(), CV_32FC1);
  const double cos_grazing = std::cos(p.grazing_angle_deg * 3.14159265358979323846 / 180.0);
  const int band = std::max(0, p.edge_band_px);
  const double fb = fx * p.baseline;
  const int rows = depth.rows, cols = depth.cols;
  tbb::parallel_for(tbb::blocked_range<int>(0, rows, 8), [&](const tbb::blocked_range<int>& range) {
    for (int v = range.begin(); v < range.end(); ++v) {
      const float* d = depth.ptr<float>(v);
      float* o = out.ptr<float>(v);
      for (int u = 0; u < cols; ++u) {
        const double z = d[u];
        o[u] = 0.f;
        if (!(z > 0) || z < p.min_range || z > p.max_range) continue;
        if (!cos_incidence.empty() && cos_incidence.at<float>(v, u) < cos_grazing) continue;
        const uint64_t h = synth_detail::hash_combine(seed, static_cast<uint64_t>(v) * cols + u);
        // Far side of a depth jump: structured-light shadow / mixed pixels go missing.
        if (band > 0 && p.edge_dropout > 0) {
          const double jump = p.edge_jump + p.edge_jump_per_m * z;
          bool near_edge = false;
          for (int dv = -band; dv <= band && !near_edge; ++dv)
            for (int du = -band; du <= band; ++du) {
              const int uu = u + du, vv = v + dv;
              if (uu < 0 || vv < 0 || uu >= cols || vv >= rows || (du == 0 && dv == 0)) continue;
              const float n = depth.at<float>(vv, uu);
              if (n > 0 && z - n > jump) {
                near_edge = true;
                break;
              }
            }
          if (near_edge && synth_detail::hash_unit(synth_detail::splitmix64(h ^ 0xed6eULL)) < p.edge_dropout) continue;
        }
        // Axial Gaussian noise (Box-Muller from two hashed uniforms).
        const double u1 = std::max(synth_detail::hash_unit(synth_detail::splitmix64(h + 1)), 1e-300);
        const double u2 = synth_detail::hash_unit(synth_detail::splitmix64(h + 2));
        const double gauss = std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
        double zn = z + depth_noise_sigma(p, z) * gauss;
        if (p.quantise_disparity && fb > 0 && p.disparity_step_px > 0 && zn > 0) {
          const double disparity = fb / zn;
          const double q = std::round(disparity / p.disparity_step_px) * p.disparity_step_px;
          zn = q > 0 ? fb / q : 0.0;
        }
        if (zn < p.min_range || zn > p.max_range) continue;
        o[u] = static_cast<float>(zn);
      }
    }
  });
  return out;
}

}  // namespace semap
