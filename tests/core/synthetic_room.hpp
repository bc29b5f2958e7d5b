#pragma once
// Labelled synthetic room meshes and hand-held trajectories with a known up and floor height,
// for the gravity estimate and the semantic consistency metrics (issue 38).
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "semap/core/labels.hpp"
#include "semap/core/point_cloud.hpp"
#include "semap/core/pose.hpp"

namespace semap::test {

/// Appends the rectangle origin + s*u + t*v (s, t in [0, 1]) as a grid of about spacing_m,
/// every vertex labelled `label` and jittered by noise_m (Gaussian, fixed seed per call order).
/// `flip` reverses the winding.
inline void add_rectangle(TriangleMesh& mesh, const Eigen::Vector3d& origin, const Eigen::Vector3d& u,
                          const Eigen::Vector3d& v, Label label, double spacing_m = 0.1, double noise_m = 0.0,
                          bool flip = false) {
  static std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  const int nu = std::max(1, static_cast<int>(std::ceil(u.norm() / spacing_m)));
  const int nv = std::max(1, static_cast<int>(std::ceil(v.norm() / spacing_m)));
  const auto base = static_cast<uint32_t>(mesh.vertices.size());
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      Eigen::Vector3d p = origin + u * i / nu + v * j / nv;
      if (noise_m > 0) p += noise_m * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      mesh.vertices.points.push_back(p.cast<float>());
      mesh.vertices.labels.push_back(id(label));
    }
  auto at = [&](int i, int j) { return base + static_cast<uint32_t>(j * (nu + 1) + i); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      std::array<uint32_t, 3> a{at(i, j), at(i + 1, j), at(i + 1, j + 1)}, b{at(i, j), at(i + 1, j + 1), at(i, j + 1)};
      if (flip) std::swap(a[1], a[2]), std::swap(b[1], b[2]);
      mesh.triangles.push_back(a);
      mesh.triangles.push_back(b);
    }
}

struct RoomParts {
  bool floor = true, walls = true, ceiling = true, table = true;
  double size_x_m = 5.0, size_y_m = 4.0, height_m = 2.5;
  double table_height_m = 0.75;
  double noise_m = 0.005;
};

/// A z-up room [0, sx] x [0, sy] x [0, h]: floor at z = 0, four walls, ceiling, a 1.2 x 0.8 m
/// table top at table_height_m. Windings alternate per part (real meshes' signs may vary).
inline TriangleMesh room_mesh(const RoomParts& r = {}) {
  TriangleMesh m;
  const Eigen::Vector3d X = Eigen::Vector3d::UnitX(), Y = Eigen::Vector3d::UnitY(), Z = Eigen::Vector3d::UnitZ();
  const double sx = r.size_x_m, sy = r.size_y_m, h = r.height_m;
  if (r.floor) add_rectangle(m, {0, 0, 0}, sx * X, sy * Y, Label::kFloor, 0.1, r.noise_m);
  if (r.ceiling) add_rectangle(m, {0, 0, h}, sx * X, sy * Y, Label::kCeiling, 0.1, r.noise_m, true);
  if (r.walls) {
    add_rectangle(m, {0, 0, 0}, sx * X, h * Z, Label::kWall, 0.1, r.noise_m);
    add_rectangle(m, {0, sy, 0}, sx * X, h * Z, Label::kWall, 0.1, r.noise_m, true);
    add_rectangle(m, {0, 0, 0}, sy * Y, h * Z, Label::kWall, 0.1, r.noise_m, true);
    add_rectangle(m, {sx, 0, 0}, sy * Y, h * Z, Label::kWall, 0.1, r.noise_m);
  }
  if (r.table) add_rectangle(m, {1.0, 1.0, r.table_height_m}, 1.2 * X, 0.8 * Y, Label::kTable, 0.05, r.noise_m);
  return m;
}

/// Hand-held cameras at height_m above the room centre's floor, on a circle of 1 m, looking
/// outward, pitched down by pitch_deg and rolling roll_bias_deg +- roll_deg, over `arc_deg` of
/// the circle (a partial arc biases the cameras' mean up axis toward the direction they look).
inline Trajectory handheld_trajectory(double arc_deg = 360.0, double pitch_deg = 20.0, double roll_deg = 15.0,
                                      double roll_bias_deg = 0.0, double height_m = 1.5,
                                      const Eigen::Vector3d& centre = {2.5, 2.0, 0.0}) {
  Trajectory t;
  constexpr int kPoses = 120;
  const double rad = std::numbers::pi / 180.0;
  for (int i = 0; i < kPoses; ++i) {
    const double yaw = arc_deg * rad * i / kPoses;
    const Eigen::Vector3d forward(std::cos(yaw), std::sin(yaw), 0.0), down(0, 0, -1);
    Eigen::Matrix3d level;
    level.col(0) = down.cross(forward);  // x = y cross z (right)
    level.col(1) = down;
    level.col(2) = forward;
    const double roll = roll_bias_deg * rad + roll_deg * rad * std::sin(7.0 * i / kPoses * 2.0 * std::numbers::pi);
    StampedPose p;
    p.timestamp = i / 30.0;
    p.T_world_camera.linear() = level * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                                Eigen::AngleAxisd(-pitch_deg * rad, Eigen::Vector3d::UnitX()).toRotationMatrix();
    p.T_world_camera.translation() = centre + forward + Eigen::Vector3d(0, 0, height_m);
    t.push_back(p);
  }
  return t;
}

/// Moves a mesh and a trajectory into the world frame T (the room's z-up frame -> world).
inline void transform(const Pose& T, TriangleMesh& mesh, Trajectory& trajectory) {
  for (auto& p : mesh.vertices.points) p = (T * p.cast<double>()).cast<float>();
  for (auto& p : trajectory) p.T_world_camera = T * p.T_world_camera;
}

}  // namespace semap::test
