#include "semap/core/camera.hpp"

#include <cmath>
#include <cstdio>

#include "semap/core/error.hpp"
#include "core/camera_difference.hpp"

namespace semap {

namespace {

void check_intrinsics(const PinholeIntrinsics& k, const std::string& source, const std::string& prefix) {
  using L = CameraLimits;
  const auto fail = [&](const std::string& key, double value, const std::string& why) {
    throw Error(source, "camera " + prefix + key + " = " + compact_number(value) + " " + why);
  };
  for (const auto& [key, size] : {std::pair{"width", k.width}, std::pair{"height", k.height}})
    if (size < L::kMinSize || size > L::kMaxSize)
      fail(key, size, "is outside " + std::to_string(L::kMinSize) + ".." + std::to_string(L::kMaxSize) + " pixels");
  if (double(k.width) * k.height > L::kMaxPixels)
    fail("width x height", double(k.width) * k.height, "pixels is more than " + compact_number(L::kMaxPixels));
  const auto check_focal = [&](const char* key, double f, int size, const char* axis) {
    const double lo = L::kMinFocalPerSize * size, hi = L::kMaxFocalPerSize * size;
    if (!std::isfinite(f) || f < lo || f > hi)
      fail(key, f, "is outside " + compact_number(lo) + ".." + compact_number(hi) + " pixels (" +
                       compact_number(L::kMinFocalPerSize) + ".." + compact_number(L::kMaxFocalPerSize) + " x the " +
                       axis + " " + std::to_string(size) + ", a field of view of about 170 to 1 degrees)");
  };
  check_focal("fx", k.fx, k.width, "width");
  check_focal("fy", k.fy, k.height, "height");
  const auto check_centre = [&](const char* key, double c, int size, const char* axis) {
    if (!std::isfinite(c) || c < 0 || c > size)
      fail(key, c, std::string("is outside the image (0..") + std::to_string(size) + ", the " + axis +
                       "): the principal point must lie inside the image");
  };
  check_centre("cx", k.cx, k.width, "width");
  check_centre("cy", k.cy, k.height, "height");
}

}  // namespace

void validate_camera(const CameraModel& camera, const std::string& source) {
  using L = CameraLimits;
  check_intrinsics(camera.depth, source, "");
  const double s = camera.depth_scale;
  if (!std::isfinite(s) || s < L::kMinDepthScale || s > L::kMaxDepthScale)
    throw Error(source, "camera depth_scale = " + compact_number(s) + " is outside " + compact_number(L::kMinDepthScale) +
                            ".." + compact_number(L::kMaxDepthScale) + " raw units per metre");
  for (double d : camera.distortion)
    if (!std::isfinite(d) || std::abs(d) > L::kMaxDistortion)
      throw Error(source, "camera distortion coefficient " + compact_number(d) + " is not a number within +-" +
                              compact_number(L::kMaxDistortion));
  if (!camera.colour) return;
  check_intrinsics(camera.colour->intrinsics, source, "colour.");
  const Pose& T = camera.colour->T_depth_colour;
  if (!T.matrix().allFinite() || T.translation().norm() > L::kMaxColourBaseline)
    throw Error(source, "camera colour.T_depth_colour baseline = " + compact_number(T.translation().norm()) +
                            " m is more than " + compact_number(L::kMaxColourBaseline) + " m");
  // Issue 44: the readers check the extrinsic files they parse; a camera from elsewhere (a saved
  // map's camera section, the Python API) only here. Same tolerance as the readers.
  if (!is_valid_pose(T, 1e-3))
    throw Error(source, "camera colour.T_depth_colour is not a rigid transform (rotation not orthonormal)");
}

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

namespace {
std::string exact(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}
void add_difference(std::string& out, const char* name, double given, double expected) {
  if (given == expected || (std::isnan(given) && std::isnan(expected))) return;
  out += (out.empty() ? "" : ", ") + std::string(name) + " " + exact(given) + " vs " + exact(expected);
}
}  // namespace

std::string describe_camera_difference(const PinholeIntrinsics& given, const PinholeIntrinsics& expected) {
  std::string out;
  if (given.width != expected.width || given.height != expected.height)
    out += "size " + std::to_string(given.width) + "x" + std::to_string(given.height) + " vs " +
           std::to_string(expected.width) + "x" + std::to_string(expected.height);
  add_difference(out, "fx", given.fx, expected.fx);
  add_difference(out, "fy", given.fy, expected.fy);
  add_difference(out, "cx", given.cx, expected.cx);
  add_difference(out, "cy", given.cy, expected.cy);
  return out;
}

std::string describe_camera_difference(const CameraModel& given, const CameraModel& expected) {
  std::string out = describe_camera_difference(given.depth, expected.depth);
  static constexpr const char* kNames[5] = {"k1", "k2", "p1", "p2", "k3"};
  for (size_t k = 0; k < 5; ++k) add_difference(out, kNames[k], given.distortion[k], expected.distortion[k]);
  return out;
}

}  // namespace semap
