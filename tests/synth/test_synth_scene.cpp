// Scene, renderer and trajectory of the synthetic world.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <map>
#include <set>

#include "semap/core/labels.hpp"
#include "synth/renderer.hpp"
#include "synth/scene.hpp"
#include "synth/trajectory.hpp"

namespace semap {
namespace {

Pose look_pose(const Eigen::Vector3d& position, const Eigen::Vector3d& forward_in, const Eigen::Vector3d& up_hint) {
  const Eigen::Vector3d forward = forward_in.normalized();
  const Eigen::Vector3d right = forward.cross(up_hint).normalized();
  Pose T = Pose::Identity();
  T.linear().col(0) = right;
  T.linear().col(1) = forward.cross(right);
  T.linear().col(2) = forward;
  T.translation() = position;
  return T;
}

TEST(SynthRenderer, FloorDepthIsExact) {
  const SyntheticScene room = make_empty_room(3);
  const PinholeIntrinsics K = synth_intrinsics(640, 480);
  // Straight down from 1.2 m: every pixel sees the floor at depth 1.2.
  const Pose T = look_pose({3.0, 2.5, 1.2}, {0, 0, -1}, {0, 1, 0});
  const RenderedFrame f = render(room, T, K);
  double max_err = 0;
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u) {
      ASSERT_EQ(f.labels.at<uint8_t>(v, u), id(Label::kFloor));
      ASSERT_EQ(f.instances.at<uint16_t>(v, u), 0);
      max_err = std::max(max_err, std::abs(f.depth.at<float>(v, u) - 1.2));
    }
  EXPECT_LT(max_err, 1e-3);
}

TEST(SynthRenderer, TiltedWallDepthMatchesPlaneIntersection) {
  const SyntheticScene room = make_empty_room(4);
  const PinholeIntrinsics K = synth_intrinsics(640, 480);
  // Facing the x = 0 wall from 1.5 m, yawed 12 deg and pitched 8 deg: depth = plane hit z.
  const Eigen::Vector3d o(1.5, 2.5, 1.35);
  const Eigen::Vector3d fwd(-std::cos(0.21) * std::cos(0.14), std::sin(0.21) * std::cos(0.14), -std::sin(0.14));
  const Pose T = look_pose(o, fwd, {0, 0, 1});
  const RenderedFrame f = render(room, T, K);
  double max_err = 0;
  int checked = 0;
  for (int v = 0; v < K.height; v += 3)
    for (int u = 0; u < K.width; u += 3) {
      const Eigen::Vector3d d = T.linear() * Eigen::Vector3d((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
      ASSERT_LT(d.x(), 0);
      const double z = (0.0 - o.x()) / d.x();  // ray parameter = camera depth
      const Eigen::Vector3d hit = o + z * d;
      if (hit.z() < 0.01 || hit.z() > 2.69 || hit.y() < 0.01 || hit.y() > 4.99) continue;
      ASSERT_EQ(f.labels.at<uint8_t>(v, u), id(Label::kWall));
      max_err = std::max(max_err, std::abs(f.depth.at<float>(v, u) - z));
      ++checked;
    }
  EXPECT_GT(checked, 30000);
  EXPECT_LT(max_err, 1e-3);
}

TEST(SynthRenderer, PrimitiveDepthAndLabels) {
  // A box and a sphere in front of the camera: analytic depths of their front surfaces.
  SyntheticScene scene = make_empty_room(5);
  Primitive box;
  box.center = {3.0, 1.0, 1.0};
  box.half_size = {0.2, 0.2, 0.2};
  box.label = id(Label::kBox);
  box.instance = 7;
  Primitive ball;
  ball.shape = PrimitiveShape::kSphere;
  ball.center = {3.6, 1.0, 1.0};
  ball.half_size = Eigen::Vector3d::Constant(0.15);
  ball.label = id(Label::kBowl);
  ball.instance = 8;
  scene.primitives = {box, ball};
  scene.build_acceleration();
  const PinholeIntrinsics K = synth_intrinsics(640, 480);
  const Pose T = look_pose({3.0, 3.0, 1.0}, {0, -1, 0}, {0, 0, 1});
  const RenderedFrame f = render(scene, T, K);
  // Box front face y = 1.2 -> camera depth 1.8 at the image centre.
  EXPECT_EQ(f.instances.at<uint16_t>(240, 320), 7);
  EXPECT_NEAR(f.depth.at<float>(240, 320), 1.8, 1e-4);
  // Sphere centre ray: pixel of (3.6, 1.0, 1.0); its front point is at depth 2.0 - 0.15.
  const Eigen::Vector3d pc = T.inverse() * Eigen::Vector3d(3.6, 1.0, 1.0);
  const Eigen::Vector2d px = K.project(pc);
  const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
  EXPECT_EQ(f.labels.at<uint8_t>(v, u), id(Label::kBowl));
  const Eigen::Vector3d dir = T.linear() * Eigen::Vector3d((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
  // Exact ray/sphere intersection for that pixel's ray.
  const Eigen::Vector3d oc = T.translation() - ball.center;
  const double a = dir.dot(dir), b = oc.dot(dir), c = oc.dot(oc) - 0.15 * 0.15;
  const double t = (-b - std::sqrt(b * b - a * c)) / a;
  EXPECT_NEAR(f.depth.at<float>(v, u), t, 1e-4);
}

TEST(SynthScene, ObjectsDoNotInterpenetrateAndStayInTheRoom) {
  for (uint64_t seed = 1; seed <= 8; ++seed)
    for (int k : {10, 20}) {
      const SyntheticScene s = make_scene(seed, k);
      ASSERT_EQ(static_cast<int>(s.objects.size()), k);
      for (size_t i = 0; i < s.objects.size(); ++i) {
        EXPECT_EQ(s.objects[i].instance_id, i + 1);
        for (const Eigen::Vector3d& c : s.objects[i].obb.corners())
          for (int a = 0; a < 3; ++a) {
            EXPECT_GE(c[a], -1e-6);
            EXPECT_LE(c[a], s.room.size[a] + 1e-6);
          }
        for (size_t j = i + 1; j < s.objects.size(); ++j)
          EXPECT_FALSE(s.objects[i].obb.overlaps(s.objects[j].obb))
              << "seed " << seed << " objects " << i + 1 << " and " << j + 1;
      }
      // Primitives of different instances never overlap either.
      for (size_t i = 0; i < s.primitives.size(); ++i)
        for (size_t j = i + 1; j < s.primitives.size(); ++j)
          if (s.primitives[i].instance != s.primitives[j].instance)
            EXPECT_FALSE(s.primitives[i].bounds().overlaps(s.primitives[j].bounds()));
    }
}

TEST(SynthScene, ObbOverlapTest) {
  Obb a, b;
  a.extent = b.extent = {1, 1, 1};
  b.center = {1.0, 0, 0};  // touching
  EXPECT_FALSE(a.overlaps(b));
  b.center = {0.99, 0, 0};
  EXPECT_TRUE(a.overlaps(b));
  b.rotation = Eigen::AngleAxisd(0.785398, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  b.center = {1.2, 0, 0};  // rotated 45 deg: half diagonal 0.707 reaches x = 0.49
  EXPECT_TRUE(a.overlaps(b));
  b.center = {1.25, 0, 0};
  EXPECT_FALSE(a.overlaps(b));
}

TEST(SynthScene, TenObjectSceneHasKnownClassCountsStackedAndTouching) {
  for (uint64_t seed : {1, 2, 3, 7}) {
    const SyntheticScene s = make_scene(seed, 10);
    std::map<std::string, int> counts;
    for (const SceneObject& o : s.objects) counts[std::string(class_name(o.class_id))]++;
    const std::map<std::string, int> expected{{"table", 1},  {"chair", 2}, {"sofa", 1}, {"bookcase", 1}, {"cabinet", 1},
                                              {"monitor", 1}, {"cup", 1},   {"bottle", 1}, {"box", 1}};
    EXPECT_EQ(counts, expected) << "seed " << seed;
    std::set<ClassId> classes;
    for (const SceneObject& o : s.objects) classes.insert(o.class_id);
    EXPECT_GE(classes.size(), 8u);
    int stacked = 0;
    for (const SceneObject& o : s.objects) stacked += o.support.rfind("on:", 0) == 0;
    EXPECT_GE(stacked, 4) << "monitor, cup, bottle on the table, box on the cabinet";
  }
  // Touching side by side: some pair of objects whose boxes touch (gap < 1 mm) but do not overlap.
  const SyntheticScene s = make_scene(1, 12);
  int touching = 0;
  for (size_t i = 0; i < s.objects.size(); ++i)
    for (size_t j = i + 1; j < s.objects.size(); ++j) {
      Obb grown = s.objects[i].obb;
      grown.extent.array() += 0.002;
      if (s.objects[i].support == s.objects[j].support && grown.overlaps(s.objects[j].obb) &&
          s.objects[i].support == "floor")
        ++touching;
    }
  EXPECT_GE(touching, 2) << "two chairs and two boxes touch side by side";
}

TEST(SynthScene, EveryObjectIsVisibleAlongTheLoop) {
  for (uint64_t seed : {1, 5}) {
    const SyntheticScene s = make_scene(seed, 15);
    const PinholeIntrinsics K = synth_intrinsics(320, 240);
    const Trajectory traj = make_loop_trajectory(s.room.size, 60, 30.0);
    std::map<uint16_t, int> best_pixels;
    for (const StampedPose& p : traj) {
      const RenderedFrame f = render(s, p.T_world_camera, K);
      std::map<uint16_t, int> pixels;
      for (int v = 0; v < f.instances.rows; ++v)
        for (int u = 0; u < f.instances.cols; ++u) pixels[f.instances.at<uint16_t>(v, u)]++;
      for (const auto& [i, n] : pixels) best_pixels[i] = std::max(best_pixels[i], n);
    }
    for (const SceneObject& o : s.objects)
      EXPECT_GE(best_pixels[o.instance_id], 40)
          << "seed " << seed << " instance " << o.instance_id << " (" << class_name(o.class_id) << ") barely visible";
  }
}

TEST(SynthScene, DeterministicForASeedDifferentAcrossSeeds) {
  const PinholeIntrinsics K = synth_intrinsics(160, 120);
  const Pose T = loop_pose({6, 5, 2.7}, 3, 60);
  const SyntheticScene a = make_scene(11, 12), b = make_scene(11, 12), c = make_scene(12, 12);
  const RenderedFrame fa = render(a, T, K), fb = render(b, T, K), fc = render(c, T, K);
  EXPECT_EQ(cv::norm(fa.rgb, fb.rgb, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(fa.depth, fb.depth, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(fa.labels, fb.labels, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(fa.instances, fb.instances, cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(fa.rgb, fc.rgb, cv::NORM_L1), 0);
  double moved = 0;
  for (size_t i = 0; i < a.objects.size(); ++i) moved += (a.objects[i].obb.center - c.objects[i].obb.center).norm();
  EXPECT_GT(moved, 0.5);
}

TEST(SynthTrajectory, LoopClosesWithSmallSteps) {
  const Eigen::Vector3d room(6, 5, 2.7);
  const Trajectory t = make_loop_trajectory(room, 300, 30.0);
  ASSERT_EQ(t.size(), 300u);
  double max_step = 0, max_rot = 0;
  for (size_t i = 1; i < t.size(); ++i) {
    const Pose d = t[i - 1].T_world_camera.inverse() * t[i].T_world_camera;
    max_step = std::max(max_step, d.translation().norm());
    max_rot = std::max(max_rot, rotation_angle(d));
    EXPECT_NEAR(t[i].timestamp - t[i - 1].timestamp, 1.0 / 30, 1e-9);
  }
  EXPECT_LT(max_step, 0.05);
  EXPECT_LT(max_rot * 180 / M_PI, 3.0);
  // The last frame is one step before the first: the start view is revisited.
  const Pose close = t.back().T_world_camera.inverse() * t.front().T_world_camera;
  EXPECT_LT(close.translation().norm(), 0.05);
  EXPECT_LT(rotation_angle(close) * 180 / M_PI, 3.0);
  // The camera stays inside the room, away from the walls.
  for (const StampedPose& p : t)
    for (int a = 0; a < 3; ++a) {
      EXPECT_GT(p.T_world_camera.translation()[a], 0.5);
      EXPECT_LT(p.T_world_camera.translation()[a], room[a] - 0.5);
    }
}

}  // namespace
}  // namespace semap
