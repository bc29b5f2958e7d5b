#pragma once
// The one pinhole camera model of the project. Depth images inside the program are float
// metres; the raw 16-bit scale lives here only so io/ can convert.
#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>

#include "semap/core/pose.hpp"

namespace semap {

struct PinholeIntrinsics {
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
  int width = 640, height = 480;

  Eigen::Matrix3d K() const;
  /// Pixel (u, v) with depth z (metres) -> camera-frame point.
  Eigen::Vector3d backproject(double u, double v, double z) const {
    return {(u - cx) * z / fx, (v - cy) * z / fy, z};
  }
  /// Camera-frame point -> pixel (u, v). Caller checks z > 0.
  Eigen::Vector2d project(const Eigen::Vector3d& p) const {
    return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
  }
  bool in_image(double u, double v) const { return u >= 0 && v >= 0 && u < width && v < height; }
  /// Same camera at another resolution (for image pyramids / network inputs).
  PinholeIntrinsics scaled(double factor) const;
  bool operator==(const PinholeIntrinsics&) const = default;
};

/// An RGB-D camera: depth intrinsics, depth scale, and an optional separate colour camera
/// (METHODS.md B2). When `colour` is empty, colour is registered to depth.
struct CameraModel {
  PinholeIntrinsics depth;
  /// Raw depth units per metre (TUM: 5000, 7-Scenes: 1000, YCB: 10000).
  double depth_scale = 5000.0;
  /// Lens distortion of the depth (= registered colour) image, OpenCV order k1 k2 p1 p2 k3;
  /// all zero = none. Frames are undistorted where they enter (dataset readers, Mapper::add_frame):
  /// every stage works in the pinhole image of these intrinsics (issue 16: TUM fr1's k1 = 0.26).
  std::array<double, 5> distortion = {0, 0, 0, 0, 0};
  bool has_distortion() const {
    for (double d : distortion)
      if (d != 0) return true;
    return false;
  }

  struct ColourCamera {
    PinholeIntrinsics intrinsics;
    /// Maps colour-camera coordinates into depth-camera coordinates (METHODS B2: R, T).
    Pose T_depth_colour = Pose::Identity();
  };
  std::optional<ColourCamera> colour;

  const PinholeIntrinsics& colour_intrinsics() const { return colour ? colour->intrinsics : depth; }
};

/// Physical ranges of a camera (issue 22: PCL aborts on cx = 1e12, cx = 1e6 takes 3.6 GB).
struct CameraLimits {
  static constexpr int kMinSize = 8, kMaxSize = 16384;            ///< width, height [px]
  static constexpr double kMaxPixels = double(1 << 26);           ///< width * height (the image decoder's cap)
  static constexpr double kMinFocalPerSize = 0.05;                ///< fx / width, fy / height: ~170 deg field of view
  static constexpr double kMaxFocalPerSize = 50.0;                ///< ~1.1 deg field of view
  static constexpr double kMinDepthScale = 1.0, kMaxDepthScale = 1e5;  ///< raw units per metre (1 m .. 10 um)
  static constexpr double kMaxColourBaseline = 1.0;               ///< |t| of T_depth_colour [m]
  static constexpr double kMaxDistortion = 10.0;                  ///< |k1..k3|, |p1|, |p2| (real lenses: under ~2)
};

/// Throws semap::Error(source, "camera KEY = VALUE ...: WHY") unless every magnitude is inside
/// CameraLimits: sizes, finite focal lengths within [0.05, 50] x the image size, the principal
/// point inside the image (0 <= cx <= width, 0 <= cy <= height), the depth scale, and for a
/// separate colour camera its intrinsics and a rigid T_depth_colour with a baseline under 1 m.
/// `source` names the file the camera came from (dataset.yaml, camera-intrinsics.txt).
void validate_camera(const CameraModel& camera, const std::string& source);

}  // namespace semap
