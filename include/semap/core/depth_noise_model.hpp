#pragma once
// Axial noise of a structured-light depth camera (Kinect v1, Nguyen, Izadi, Lovell 2012):
// sigma(z) = base + quadratic * (z - 0.4 m)^2, flat below 0.4 m. Used wherever a bound should
// grow with the depth's own uncertainty instead of being a fixed distance (the TSDF's label
// band; the tracker's registration checks declare the same keys).
#include <algorithm>

#include "semap/core/params.hpp"

namespace semap {

struct DepthNoiseModel {
  double base_m = 0.0012;       ///< sigma(z) at and below 0.4 m, metres
  double quadratic = 0.0019;    ///< sigma(z) growth, metres per metre^2 beyond 0.4 m
  static constexpr double kMinNoiseDepthM = 0.4;  ///< depth of the model's minimum noise

  /// sigma(z), metres. Thread safety: const.
  double sigma_m(double z_m) const {
    const double dz = std::max(0.0, z_m - kMinNoiseDepthM);
    return base_m + quadratic * dz * dz;
  }

  void visit(ParamVisitor& v) {
    v.param("depth_noise_base_m", base_m, "m", "depth noise sigma at 0.4 m (sensor model)", positive(1.0));
    v.param("depth_noise_quadratic", quadratic, "1/m", "depth noise growth: sigma(z) = base + this * (z - 0.4)^2",
            non_negative(1.0));
  }
};

}  // namespace semap
