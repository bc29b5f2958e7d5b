#pragma once
// Kinect-v1-like depth noise for synthetic frames:
//  - axial Gaussian noise sigma(z) = a + b (z - z0)^2 (Nguyen, Izadi, Lovell 2012:
//    a = 0.0012 m, b = 0.0019 m^-1, z0 = 0.4 m),
//  - missing depth at depth discontinuities (a band next to jumps) and at grazing angles,
//  - the sensor range (z < min_range or z > max_range -> 0),
//  - disparity quantisation (1/8 px sub-pixel steps of a structured-light sensor with the given
//    baseline), which makes the depth steps grow with z^2.
#include <cstdint>
#include <opencv2/core.hpp>

#include "semap/core/params.hpp"

namespace semap {

struct DepthNoiseParams {
  double sigma_a = 0.0012;          ///< m, constant term of the axial sigma
  double sigma_b = 0.0019;          ///< 1/m, quadratic term
  double sigma_z0 = 0.4;            ///< m, offset of the quadratic term
  double min_range = 0.4;           ///< m, closer -> invalid
  double max_range = 8.0;           ///< m, farther -> invalid
  double grazing_angle_deg = 78.0;  ///< incidence angles beyond this -> invalid
  double edge_jump = 0.04;          ///< m (+ edge_jump_per_m * z): a depth jump counted as an edge
  double edge_jump_per_m = 0.02;
  int edge_band_px = 1;             ///< pixels on the far side of a jump that are dropped
  double edge_dropout = 0.7;        ///< probability a band pixel is dropped
  bool quantise_disparity = true;   ///< quantise in disparity space (structured light)
  double baseline = 0.075;          ///< m, projector-camera baseline for quantisation
  double disparity_step_px = 0.125; ///< px, sub-pixel disparity resolution

  void visit(ParamVisitor& v);
};

/// sigma(z) of the axial noise (m).
double depth_noise_sigma(const DepthNoiseParams& params, double z);

/// Returns a noisy copy of `depth_m` (CV_32F metres, 0 = invalid). `cos_incidence` (CV_32F,
/// |cos| of the angle between viewing ray and surface normal) may be empty (no grazing drop).
/// `fx` is the focal length used for disparity quantisation. Deterministic for `seed`.
cv::Mat apply_depth_noise(const cv::Mat& depth_m, const cv::Mat& cos_incidence, double fx, uint64_t seed,
                          const DepthNoiseParams& params);

}  // namespace semap
