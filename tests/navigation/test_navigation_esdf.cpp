// Issue 39: the 3D distance field (navigation/esdf.hpp) against a simulated world with known
// geometry (voxblox style): a closed box room holding a sphere and a box standing on the floor,
// seen by rendered depth views from camera positions inside it, fused by the projective
// integrator. The analytic distance to the nearest surface is the ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <random>

#include "semap/navigation/distance_query.hpp"
#include "tsdf/integrator.hpp"

using namespace semap;

namespace {

const Eigen::Vector3d kRoom(4.0, 3.0, 2.5);  // the room: [0, kRoom] inside
const Eigen::Vector3d kSphereCentre(2.7, 1.8, 1.1);
constexpr double kSphereRadius = 0.4;
const Eigen::Vector3d kBoxLo(0.7, 0.9, 0.0), kBoxHi(1.5, 1.5, 0.7);  // standing on the floor

/// Signed distance of an axis-aligned box (positive outside).
double box_sdf(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const Eigen::Vector3d q = (lo - p).cwiseMax(p - hi);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

/// True distance from a point of the room's free space to the nearest surface (negative inside
/// the sphere or box, or outside the room).
double true_distance(const Eigen::Vector3d& p) {
  const double walls = std::min(p.minCoeff(), (kRoom - p).minCoeff());
  return std::min({walls, (p - kSphereCentre).norm() - kSphereRadius, box_sdf(p, kBoxLo, kBoxHi)});
}

/// Distance along a unit ray from inside the room to the first surface.
double ray_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i)  // room walls from inside
    if (d[i] > 0) t = std::min(t, (kRoom[i] - o[i]) / d[i]);
    else if (d[i] < 0) t = std::min(t, -o[i] / d[i]);
  const Eigen::Vector3d oc = o - kSphereCentre;
  const double b = oc.dot(d), c = oc.squaredNorm() - kSphereRadius * kSphereRadius, disc = b * b - c;
  if (disc >= 0 && -b - std::sqrt(disc) > 0) t = std::min(t, -b - std::sqrt(disc));
  double t_near = 0, t_far = t;  // slab test of the box
  for (int i = 0; i < 3 && t_near <= t_far; ++i) {
    if (d[i] == 0) {
      if (o[i] < kBoxLo[i] || o[i] > kBoxHi[i]) t_far = -1;
      continue;
    }
    double a = (kBoxLo[i] - o[i]) / d[i], bb = (kBoxHi[i] - o[i]) / d[i];
    if (a > bb) std::swap(a, bb);
    t_near = std::max(t_near, a), t_far = std::min(t_far, bb);
  }
  if (t_near <= t_far && t_near > 0) t = std::min(t, t_near);
  return t;
}

/// Camera at `position` looking along `forward` (no roll), x right, y down, z forward.
Pose look(const Eigen::Vector3d& position, const Eigen::Vector3d& forward) {
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized(), y = z.cross(x);
  Pose T = Pose::Identity();
  T.linear() << x, y, z;
  T.translation() = position;
  return T;
}

struct World {
  TsdfMap map;
  std::vector<Eigen::Vector3d> cameras;
};

/// Views from 6 positions at two heights, 8 headings each, pitched down and up a little.
World render_and_fuse(double voxel_m) {
  TsdfConfig config;
  config.voxel_size = voxel_m;
  config.label_layer = config.bayes_layer = config.colour_layer = false;
  config.max_depth = 6.0;
  World w{TsdfMap(config), {}};
  PinholeIntrinsics K;
  K.width = 160, K.height = 120, K.fx = K.fy = 90.0, K.cx = 79.5, K.cy = 59.5;
  auto integrator = make_integrator(IntegratorKind::projective, config);
  for (const Eigen::Vector3d& xy : {Eigen::Vector3d(0.5, 2.5, 0), Eigen::Vector3d(2.0, 0.4, 0), Eigen::Vector3d(3.6, 2.6, 0)})
    for (double height : {0.5, 1.7}) {
      const Eigen::Vector3d position(xy.x(), xy.y(), height);
      w.cameras.push_back(position);
      for (int heading = 0; heading < 8; ++heading)
        for (double pitch : {-0.5, 0.3}) {
          const double yaw = heading * M_PI / 4;
          const Pose T = look(position, {std::cos(yaw), std::sin(yaw), pitch});
          IntegrationInput in;
          in.intrinsics = K;
          in.T_world_camera = T;
          in.depth = cv::Mat(K.height, K.width, CV_32FC1);
          for (int v = 0; v < K.height; ++v)
            for (int u = 0; u < K.width; ++u) {
              const Eigen::Vector3d ray_C = K.backproject(u, v, 1.0);  // z = 1: t along it is depth
              const double t = ray_hit(position, (T.linear() * ray_C).normalized());
              in.depth.at<float>(v, u) = static_cast<float>(t / ray_C.norm());
            }
          integrator->integrate(w.map, in);
        }
    }
  return w;
}

/// The world at the TSDF's default voxel size, fused once per test process.
const World& world() {
  static const World w = render_and_fuse(TsdfConfig{}.voxel_size);
  return w;
}

/// Its distance field with the camera positions and the default parameters, built once.
const DistanceQuery& world_query() {
  static const DistanceQuery q(world().map, NavigationConfig{}, world().cameras);
  return q;
}

}  // namespace

TEST(NavigationEsdf, DistancesMatchTheAnalyticWorld) {
  const World& w = world();
  const double voxel = w.map.voxel_size();
  const DistanceQuery& query = world_query();
  const EsdfStats& st = query.esdf().stats();
  std::printf("esdf: %d x %d x %d cells of %.2f m, %zu free, %zu occupied, %zu carved blocks, %zu lines (%zu blocked), "
              "%.3f s, %.1f MB\n",
              st.dims.x(), st.dims.y(), st.dims.z(), st.cell_m, st.free_cells, st.occupied_cells, st.carved_blocks,
              st.lines_of_sight, st.blocked_lines, st.build_s, st.peak_bytes / 1e6);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(0, kRoom.x()), uy(0, kRoom.y()), uz(0, kRoom.z());
  size_t candidates = 0, observed = 0;
  double sum_abs = 0, max_abs = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng));
    const double truth = true_distance(p);
    if (!(truth > 0.0) || truth > 1.0) continue;  // free space up to 1 m from the surfaces
    ++candidates;
    const double d = query.distance_m(p);
    if (std::isnan(d)) continue;
    ++observed;
    sum_abs += std::abs(d - truth);
    max_abs = std::max(max_abs, std::abs(d - truth));
  }
  const double mean_abs = sum_abs / std::max<size_t>(observed, 1);
  std::printf("free points up to 1 m from a surface: %zu, observed %.3f, mean |error| %.4f m, max %.4f m (voxel %.2f m)\n",
              candidates, static_cast<double>(observed) / candidates, mean_abs, max_abs, voxel);
  EXPECT_GT(static_cast<double>(observed) / candidates, 0.9);  // the open room, not only the TSDF's band
  EXPECT_LE(mean_abs, voxel);
  EXPECT_LE(max_abs, 2 * voxel);
  // Far beyond the truncation (16 cm) in the middle of the room: the distance to the box.
  EXPECT_NEAR(query.distance_m({2.0, 1.0, 0.5}), true_distance({2.0, 1.0, 0.5}), voxel);
}

TEST(NavigationEsdf, UnknownSpaceIsNanAndIsFreeFollowsTheTruth) {
  const DistanceQuery& query = world_query();
  std::mt19937 rng(11);
  // Outside the room (beyond the walls' observed back band) and deep inside the box: unknown.
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  size_t outside = 0, outside_nan = 0;
  for (int i = 0; i < 2000; ++i) {
    Eigen::Vector3d p(u(rng) + 2.0, u(rng) + 1.5, u(rng) + 1.2);
    p[i % 3] += (i % 2 ? 1 : -1) * (0.5 * kRoom[i % 3] + 0.6);  // 0.3-0.9 m behind a wall
    ++outside;
    outside_nan += std::isnan(query.distance_m(p));
  }
  EXPECT_EQ(outside_nan, outside);
  EXPECT_TRUE(std::isnan(query.distance_m(0.5 * (kBoxLo + kBoxHi))));
  EXPECT_FALSE(query.is_free(0.5 * (kBoxLo + kBoxHi), 0.0));
  // is_free(p, r) against the analytic answer (truth >= r) on observed points of the room.
  std::uniform_real_distribution<double> ux(0, kRoom.x()), uy(0, kRoom.y()), uz(0, kRoom.z()), ur(0.05, 1.0);
  size_t asked = 0, agree = 0, free_truth = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d p(ux(rng), uy(rng), uz(rng));
    if (std::isnan(query.distance_m(p))) continue;
    const double r = ur(rng);
    const bool truth = true_distance(p) >= r;
    ++asked;
    free_truth += truth;
    agree += query.is_free(p, r) == truth;
  }
  std::printf("is_free: %zu observed points, %zu free in truth, agreement %.4f\n", asked, free_truth,
              static_cast<double>(agree) / asked);
  EXPECT_GT(free_truth, asked / 10);
  EXPECT_GE(static_cast<double>(agree) / asked, 0.99);
}

TEST(NavigationEsdf, WithoutCamerasOnlyTheTsdfBandIsObservedAndMemoryIsBounded) {
  const World& w = world();
  const DistanceQuery band_only(w.map);
  EXPECT_TRUE(std::isnan(band_only.distance_m({2.0, 1.0, 1.2})));  // the open middle: no voxels there
  EXPECT_NEAR(band_only.distance_m({2.0, 1.0, 0.06}), 0.06, w.map.voxel_size());  // above the floor
  // A memory limit below the full grid's needs coarser cells, and the build stays inside it.
  NavigationConfig tight;
  tight.esdf_max_memory_mb = 2.0;
  const DistanceQuery coarse(w.map, tight, w.cameras);
  const EsdfStats& st = coarse.esdf().stats();
  EXPECT_GT(st.cell_m, w.map.voxel_size() * 1.5);
  EXPECT_LE(st.peak_bytes, 2.0 * 1024 * 1024);
  EXPECT_NEAR(coarse.distance_m({2.0, 1.0, 0.5}), true_distance({2.0, 1.0, 0.5}), 2 * st.cell_m);
  // Beyond esdf_max_distance_m: "at least" the maximum, and larger balls are never free.
  NavigationConfig short_range;
  short_range.esdf_max_distance_m = 0.3;
  const DistanceQuery capped(w.map, short_range, w.cameras);
  EXPECT_NEAR(capped.distance_m({2.0, 1.5, 1.25}), 0.3, 1e-6);
  EXPECT_FALSE(capped.is_free({2.0, 1.5, 1.25}, 0.5));
}
