#include "semap/io/trajectory_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "io/text_util.hpp"

namespace semap {

namespace {
// Quaternions further than this from unit norm are rejected, nearer ones are normalised.
constexpr double kQuaternionNormTolerance = 1e-3;
// Positions beyond this are refused: past float range they became "pose is not finite" deep in
// the pipeline, without the file's name (issue 44, class 8). 1e9 m leaves room for any
// georeferenced (UTM, ECEF) trajectory. README, reliability.
constexpr double kMaxPositionM = 1e9;
}  // namespace

Trajectory parse_tum_trajectory(const std::string& text, const std::string& source) {
  using namespace io_detail;
  Trajectory trajectory;
  for_each_line(text, [&](std::string_view line, size_t line_no) {
    if (is_blank_or_comment(line)) return;
    const auto fields = split_fields(line);
    if (fields.size() != 8)
      throw Error(where(source, line_no), "expected 8 numbers 'timestamp tx ty tz qx qy qz qw', got " +
                                              std::to_string(fields.size()) + " fields");
    double v[8];
    for (int k = 0; k < 8; ++k) {
      const auto value = parse_double(fields[k]);
      if (!value) throw Error(where(source, line_no), "malformed number " + quoted_field(fields[k]));
      if (!std::isfinite(*value)) throw Error(where(source, line_no), "NaN or Inf value");
      v[k] = *value;
    }
    if (std::max({std::abs(v[1]), std::abs(v[2]), std::abs(v[3])}) > kMaxPositionM)
      throw Error(where(source, line_no), "position beyond +-1e9 m");
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);  // Eigen takes (w, x, y, z)
    if (std::abs(q.norm() - 1.0) > kQuaternionNormTolerance)
      throw Error(where(source, line_no), "quaternion is not unit (norm " + std::to_string(q.norm()) + ")");
    if (!trajectory.empty() && v[0] <= trajectory.back().timestamp)
      throw Error(where(source, line_no), v[0] == trajectory.back().timestamp
                                              ? "duplicate timestamp"
                                              : "timestamp not increasing");
    trajectory.push_back({v[0], pose_from_tq({v[1], v[2], v[3]}, q)});
  });
  return trajectory;
}

Trajectory read_tum_trajectory(const std::filesystem::path& path) {
  return parse_tum_trajectory(io_detail::read_file_bytes(path, kMaxTextFileBytes, "trajectory file"), path.string());
}

std::string format_tum_trajectory(const Trajectory& trajectory, const std::filesystem::path& path) {
  std::string text = "# timestamp tx ty tz qx qy qz qw\n";
  char line[512];
  for (const auto& sp : trajectory) {
    if (!sp.T_world_camera.matrix().allFinite() || !std::isfinite(sp.timestamp))
      throw Error(path, "refusing to write a non-finite pose");
    const Eigen::Vector3d t = sp.T_world_camera.translation();
    Eigen::Quaterniond q(sp.T_world_camera.linear());
    q.normalize();
    if (q.w() < 0) q.coeffs() *= -1.0;  // canonical sign, so files are reproducible
    std::snprintf(line, sizeof line, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", sp.timestamp, t.x(),
                  t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
    text += line;
  }
  return text;
}

void write_tum_trajectory(const std::filesystem::path& path, const Trajectory& trajectory) {
  write_file_atomic(path, format_tum_trajectory(trajectory, path));
}

}  // namespace semap
