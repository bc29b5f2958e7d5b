#pragma once
// What differs between two cameras, for mismatch messages (issue 44, class 8).
#include <string>

#include "semap/core/camera.hpp"

namespace semap {

/// Each differing value of `given` and `expected` at full precision ("fx 525.00000000000011 vs
/// 525"), so that two different cameras never print as equal. Empty when equal. Thread-safe.
std::string describe_camera_difference(const PinholeIntrinsics& given, const PinholeIntrinsics& expected);
/// The depth intrinsics' and the distortion coefficients' differences.
std::string describe_camera_difference(const CameraModel& given, const CameraModel& expected);

}  // namespace semap
