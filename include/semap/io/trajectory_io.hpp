#pragma once
// TUM trajectory files: "timestamp tx ty tz qx qy qz qw", '#' comments, camera-to-world.
#include <filesystem>
#include <string>

#include "semap/core/pose.hpp"

namespace semap {

/// Reads a TUM trajectory. Throws semap::Error naming the file and line for malformed lines,
/// NaN/Inf values, non-unit quaternions (|q| off by > 1e-3; nearly-unit ones are normalised),
/// or non-increasing timestamps.
Trajectory read_tum_trajectory(const std::filesystem::path& path);
/// Parses trajectory text (`source` names it in messages). Same rules as above.
Trajectory parse_tum_trajectory(const std::string& text, const std::string& source);
/// The text write_tum_trajectory writes (`name` only for messages: a non-finite pose throws).
std::string format_tum_trajectory(const Trajectory& trajectory, const std::filesystem::path& name);
/// Writes atomically, full double precision.
void write_tum_trajectory(const std::filesystem::path& path, const Trajectory& trajectory);

}  // namespace semap
