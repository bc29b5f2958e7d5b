#include <gtest/gtest.h>

#include <cmath>

#include "semap/core/camera.hpp"
#include "semap/core/labels.hpp"
#include "semap/core/point_cloud.hpp"
#include "semap/core/pose.hpp"

namespace semap {

TEST(Camera, BackprojectProjectRoundTrip) {
  PinholeIntrinsics k{517.3, 516.5, 318.6, 255.3, 640, 480};
  const Eigen::Vector3d p = k.backproject(100.5, 200.25, 1.7);
  const Eigen::Vector2d uv = k.project(p);
  EXPECT_NEAR(uv.x(), 100.5, 1e-9);
  EXPECT_NEAR(uv.y(), 200.25, 1e-9);
  EXPECT_DOUBLE_EQ(p.z(), 1.7);
}

TEST(Camera, ScaledKeepsPixelCentres) {
  PinholeIntrinsics k{500, 500, 319.5, 239.5, 640, 480};
  const PinholeIntrinsics h = k.scaled(0.5);
  EXPECT_EQ(h.width, 320);
  EXPECT_EQ(h.height, 240);
  EXPECT_DOUBLE_EQ(h.cx, 159.5);
  // The same ray hits the same relative image position.
  const Eigen::Vector3d p(0.3, -0.2, 2.0);
  EXPECT_NEAR(h.project(p).x(), (k.project(p).x() + 0.5) * 0.5 - 0.5, 1e-9);
}

TEST(Pose, ValidityChecks) {
  Pose p = pose_from_tq({1, 2, 3}, Eigen::Quaterniond(0.9, 0.1, 0.2, 0.3));
  EXPECT_TRUE(is_valid_pose(p));
  p.matrix()(0, 3) = std::nan("");
  EXPECT_FALSE(is_valid_pose(p));
  Pose s = Pose::Identity();
  s.linear() *= 2.0;
  EXPECT_FALSE(is_valid_pose(s));
  EXPECT_NEAR(rotation_angle(pose_from_tq({0, 0, 0}, Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ())))), 0.5, 1e-12);
}

TEST(Pose, InterpolationFollowsTheShortestRotationAndTheStraightLine) {
  const auto about_z = [](double rad) { return Eigen::Quaterniond(Eigen::AngleAxisd(rad, Eigen::Vector3d::UnitZ())); };
  const Pose a = pose_from_tq({0, 0, 0}, about_z(0.2)), b = pose_from_tq({2, -4, 1}, about_z(1.0));
  const Pose quarter = interpolate_pose(a, b, 0.25);
  EXPECT_TRUE(is_valid_pose(quarter));
  EXPECT_NEAR((quarter.translation() - Eigen::Vector3d(0.5, -1.0, 0.25)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(rotation_angle(a.inverse() * quarter), 0.2, 1e-9);
  EXPECT_TRUE(interpolate_pose(a, b, 0.0).isApprox(a, 1e-12));
  EXPECT_TRUE(interpolate_pose(a, b, 1.0).isApprox(b, 1e-12));
  // Past b along the same rotation axis and line.
  const Pose beyond = interpolate_pose(a, b, 1.5);
  EXPECT_NEAR(rotation_angle(b.inverse() * beyond), 0.4, 1e-9);
  EXPECT_NEAR((beyond.translation() - Eigen::Vector3d(3, -6, 1.5)).norm(), 0.0, 1e-12);
}

TEST(Labels, NamesRoundTripAndUnknownIsOther) {
  for (int c = 0; c < kNumClasses; ++c) {
    const auto back = class_from_name(class_name(static_cast<ClassId>(c)));
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(*back, c);
  }
  EXPECT_EQ(class_name(250), "other");
  EXPECT_FALSE(class_from_name("no-such-class").has_value());
  EXPECT_TRUE(is_stuff(id(Label::kWall)));
  EXPECT_FALSE(is_stuff(id(Label::kChair)));
}

TEST(PointCloud, PushBackKeepsAttributesConsistent) {
  PointCloud a;
  a.points = {{0, 0, 0}, {1, 1, 1}};
  a.labels = {3, 4};
  PointCloud b;
  b.push_back_from(a, 1);
  EXPECT_TRUE(b.consistent());
  EXPECT_EQ(b.labels.at(0), 4);
  a.colours.resize(1);
  EXPECT_FALSE(a.consistent());
}

}  // namespace semap
