#include "semap/core/camera.hpp"

namespace semap {

Eigen::Matrix3d PinholeIntrinsics::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

PinholeIntrinsics PinholeIntrinsics::scaled(double factor) const {
  PinholeIntrinsics s = *this;
  s.fx *= factor;
  s.fy *= factor;
  // Pixel centres: continuous coordinate c maps to (c + 0.5) * f - 0.5.
  s.cx = (cx + 0.5) * factor - 0.5;
  s.cy = (cy + 0.5) * factor - 0.5;
  s.width = static_cast<int>(width * factor + 0.5);
  s.height = static_cast<int>(height * factor + 0.5);
  return s;
}

}  // namespace semap
