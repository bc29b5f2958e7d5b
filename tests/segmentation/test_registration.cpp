// Colour <-> depth registration (METHODS B2). What is tested:
//  1. identity extrinsic + equal intrinsics -> the lookup map is the identity, images unchanged;
//  2. the two Asus cameras of ../shared/data/ycb_video_0000/cameras/asus-uw.json (colour
//     1066/1067 px focal, depth 568 px, 2.6 cm baseline): YCB depth is registered to colour, so
//     its points are known in the colour camera. We move them with the JSON extrinsic into the
//     depth camera and z-buffer them into a depth image, remembering which colour pixel each
//     depth pixel came from (known geometry). colour_lookup_map() must recover those colour
//     pixels, and the registered YCB labels/colours must match the source pixels' ones.
//     The same check with an identity extrinsic must fail (the test can fail).
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "segmentation/registration.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

TEST(Registration, IdentityExtrinsicGivesIdentityMap) {
  CameraModel cam;
  cam.depth = {500, 500, 159.5, 119.5, 320, 240};
  cam.colour = CameraModel::ColourCamera{cam.depth, Pose::Identity()};
  EXPECT_FALSE(needs_registration(cam));
  cv::Mat depth(240, 320, CV_32FC1, cv::Scalar(1.5f));
  depth(cv::Rect(10, 10, 5, 5)).setTo(0.f);
  const cv::Mat map = colour_lookup_map(depth, cam);
  double max_err = 0;
  for (int v = 0; v < 240; ++v)
    for (int u = 0; u < 320; ++u) {
      const cv::Vec2f m = map.at<cv::Vec2f>(v, u);
      if (depth.at<float>(v, u) == 0.f) {
        EXPECT_EQ(m[0], -1.f);
        continue;
      }
      max_err = std::max({max_err, std::abs(m[0] - u * 1.0), std::abs(m[1] - v * 1.0)});
    }
  EXPECT_LT(max_err, 1e-3);
  cv::Mat labels(240, 320, CV_8UC1);
  cv::randu(labels, 0, 30);
  const cv::Mat reg = register_image(labels, map, cv::INTER_NEAREST);
  cv::Mat expected = labels.clone();
  expected.setTo(0, depth == 0);
  EXPECT_EQ(cv::countNonZero(reg != expected), 0);
}

struct AsusRig {
  PinholeIntrinsics colour, depth;
  Pose T_depth_colour = Pose::Identity();
};

AsusRig read_asus_rig(const std::filesystem::path& path) {
  std::ifstream in(path);
  const auto j = nlohmann::json::parse(in);
  const auto& cams = j.at("rig").at("camera");
  auto intr = [](const nlohmann::json& c) {
    const auto& m = c.at("camera_model");
    const auto& p = m.at("params");
    return PinholeIntrinsics{p[0].get<double>(), p[1].get<double>(), p[2].get<double>(), p[3].get<double>(),
                             m.at("width").get<int>(), m.at("height").get<int>()};
  };
  AsusRig rig;
  rig.colour = intr(cams[0]);  // fu 1066.778: the colour camera YCB-Video is registered to
  rig.depth = intr(cams[1]);   // fu 567.6: the depth (IR) camera, the rig origin (identity pose)
  // The colour camera's "pose" [R|t] in the rig (= depth camera) frame: colour -> depth.
  const auto& pose = cams[0].at("pose");
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rig.T_depth_colour.matrix()(r, c) = pose[r][c].get<double>();
    rig.T_depth_colour.matrix()(r, 3) = pose[r][3].get<double>();
  }
  return rig;
}

struct RegistrationCheck {
  double median_px = 0, p95_px = 0;
  double label_agreement = 0;
  int pixels = 0;
};

// Builds the depth-camera image from YCB's colour-registered depth using `true_T`, then
// registers with `used_T` and compares with the known source pixels.
RegistrationCheck check_ycb(const AsusRig& rig, const Pose& true_T, const Pose& used_T, const cv::Mat& depth_c,
                            const cv::Mat& labels_c) {
  cv::Mat depth_d = cv::Mat::zeros(rig.depth.height, rig.depth.width, CV_32FC1);
  cv::Mat source(depth_d.size(), CV_32FC2, cv::Scalar(-1, -1));
  for (int v = 0; v < depth_c.rows; ++v)
    for (int u = 0; u < depth_c.cols; ++u) {
      const float z = depth_c.at<float>(v, u);
      if (!(z > 0)) continue;
      const Eigen::Vector3d pd = true_T * rig.colour.backproject(u, v, z);
      const Eigen::Vector2d px = rig.depth.project(pd);
      const int du = int(std::lround(px.x())), dv = int(std::lround(px.y()));
      if (du < 0 || dv < 0 || du >= depth_d.cols || dv >= depth_d.rows) continue;
      float& zb = depth_d.at<float>(dv, du);
      // Keep the nearest surface; among equals, the point projecting closest to the pixel centre.
      if (zb == 0 || pd.z() < zb - 1e-3) {
        zb = float(pd.z());
        source.at<cv::Vec2f>(dv, du) = cv::Vec2f(float(u), float(v));
      }
    }
  CameraModel cam;
  cam.depth = rig.depth;
  cam.colour = CameraModel::ColourCamera{rig.colour, used_T};
  EXPECT_TRUE(needs_registration(cam));
  const cv::Mat map = colour_lookup_map(depth_d, cam);
  const cv::Mat reg_labels = register_image(labels_c, map, cv::INTER_NEAREST);
  std::vector<double> errors;
  int agree = 0;
  for (int v = 0; v < depth_d.rows; ++v)
    for (int u = 0; u < depth_d.cols; ++u) {
      const cv::Vec2f s = source.at<cv::Vec2f>(v, u), m = map.at<cv::Vec2f>(v, u);
      if (s[0] < 0) continue;
      if (m[0] < 0) {
        errors.push_back(1e3);
        continue;
      }
      errors.push_back(std::hypot(s[0] - m[0], s[1] - m[1]));
      agree += reg_labels.at<uint8_t>(v, u) == labels_c.at<uint8_t>(int(s[1]), int(s[0]));
    }
  RegistrationCheck c;
  c.pixels = int(errors.size());
  if (errors.empty()) return c;
  std::sort(errors.begin(), errors.end());
  c.median_px = errors[errors.size() / 2];
  c.p95_px = errors[errors.size() * 95 / 100];
  c.label_agreement = double(agree) / errors.size();
  return c;
}

TEST(Registration, YcbAsusRigKnownGeometry) {
  SEMAP_REQUIRE_DATA(root, "ycb_video_0000");
  const AsusRig rig = read_asus_rig(root / "cameras/asus-uw.json");
  EXPECT_NEAR(rig.T_depth_colour.translation().norm(), 0.0263, 1e-3);
  const cv::Mat raw = cv::imread((root / "data/0000/000001-depth.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat raw_labels = cv::imread((root / "data/0000/000001-label.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw.type(), CV_16UC1);
  ASSERT_EQ(raw_labels.type(), CV_8UC1);
  cv::Mat depth_c;
  raw.convertTo(depth_c, CV_32F, 1.0 / 10000.0);  // YCB-Video depth: 1/10000 m
  const RegistrationCheck good = check_ycb(rig, rig.T_depth_colour, rig.T_depth_colour, depth_c, raw_labels);
  const RegistrationCheck wrong = check_ycb(rig, rig.T_depth_colour, Pose::Identity(), depth_c, raw_labels);
  std::printf("YCB asus-uw registration: %d depth pixels, JSON extrinsic median %.2f px p95 %.2f px label agreement %.4f;"
              " identity extrinsic median %.2f px p95 %.2f px label agreement %.4f\n",
              good.pixels, good.median_px, good.p95_px, good.label_agreement, wrong.median_px, wrong.p95_px,
              wrong.label_agreement);
  EXPECT_GT(good.pixels, 50000);
  // A depth pixel spans ~1.9 colour pixels, so the known source is within about one colour pixel.
  EXPECT_LT(good.median_px, 1.0);
  EXPECT_LT(good.p95_px, 2.0);
  EXPECT_GT(good.label_agreement, 0.98);
  EXPECT_GT(wrong.median_px, 10.0);
}

}  // namespace
}  // namespace semap
