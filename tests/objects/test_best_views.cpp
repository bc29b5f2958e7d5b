// objects/best_views (issue 43): the view kept per object is its largest unoccluded one, the
// crop shows the object and stays small, and views of objects gone from the map are dropped.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "objects/best_views.hpp"

namespace semap {
namespace {

PinholeIntrinsics small_camera() {
  PinholeIntrinsics c;
  c.fx = c.fy = 100.0;
  c.cx = 79.5;
  c.cy = 59.5;
  c.width = 160;
  c.height = 120;
  return c;
}

/// A 0.4 m square of points facing the camera (identity pose) at z = 2 m, 2 cm apart.
ObjectInstance square_object(uint32_t id) {
  ObjectInstance o;
  o.id = id;
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j) o.points.emplace_back(-0.2f + 0.02f * i, -0.2f + 0.02f * j, 2.0f);
  return o;
}

/// Depth 2 m everywhere (the object's depth), the object's pixels (seen from the identity pose)
/// in `colour`; `occluded_columns`: image columns from the left hidden by something at 1 m.
Frame frame_seeing(const PinholeIntrinsics& camera, const cv::Vec3b& colour, int occluded_columns) {
  Frame f;
  f.depth = cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
  f.rgb = cv::Mat(camera.height, camera.width, CV_8UC3, cv::Scalar(128, 128, 128));
  f.rgb(cv::Rect(69, 49, 22, 22)).setTo(colour);  // the square spans +-10 px around the centre
  if (occluded_columns > 0) {
    f.depth(cv::Rect(0, 0, occluded_columns, camera.height)).setTo(1.0f);
    f.rgb(cv::Rect(0, 0, occluded_columns, camera.height)).setTo(cv::Scalar(255, 0, 0));
  }
  return f;
}

/// The colour at the centre of the kept crop.
cv::Vec3b centre_colour(const std::string& jpeg) {
  const cv::Mat image = cv::imdecode(std::vector<uint8_t>(jpeg.begin(), jpeg.end()), cv::IMREAD_COLOR);
  EXPECT_FALSE(image.empty());
  return image.empty() ? cv::Vec3b() : image.at<cv::Vec3b>(image.rows / 2, image.cols / 2);
}

bool near(const cv::Vec3b& a, const cv::Vec3b& b) { return cv::norm(cv::Vec3i(a) - cv::Vec3i(b)) < 40; }

TEST(BestViews, KeepsTheLargestUnoccludedViewAndItsCrop) {
  const PinholeIntrinsics camera = small_camera();
  const cv::Vec3b red(0, 0, 255), green(0, 200, 0);
  BestViews views(camera);
  const std::vector<ObjectInstance> objects{square_object(7)};
  // Half hidden (columns up to the square's middle at x = 80 px) behind something nearer.
  views.update(objects, frame_seeing(camera, red, 80), Pose::Identity());
  ASSERT_FALSE(views.jpeg(7).empty());
  EXPECT_TRUE(near(centre_colour(views.jpeg(7)), red));
  // Seen whole: a better view replaces it.
  views.update(objects, frame_seeing(camera, green, 0), Pose::Identity());
  EXPECT_TRUE(near(centre_colour(views.jpeg(7)), green));
  // Half hidden again, and cut by the image border: neither replaces the whole view.
  views.update(objects, frame_seeing(camera, red, 80), Pose::Identity());
  Pose shifted = Pose::Identity();
  shifted.translation().x() = 1.59;  // the square's middle on the left border
  views.update(objects, frame_seeing(camera, red, 0), shifted);
  EXPECT_TRUE(near(centre_colour(views.jpeg(7)), green));
}

TEST(BestViews, CropsStaySmallAndGoWithTheirObject) {
  const PinholeIntrinsics camera = small_camera();
  BestViews views(camera);
  Pose close = Pose::Identity();
  close.translation().z() = 1.55;  // 0.45 m away: the square fills 90 % of the image height
  Frame frame = frame_seeing(camera, cv::Vec3b(0, 200, 0), 0);
  frame.depth.setTo(0.45f);
  views.update({square_object(3)}, frame, close);
  const std::string jpeg = views.jpeg(3);
  ASSERT_FALSE(jpeg.empty());
  const cv::Mat image = cv::imdecode(std::vector<uint8_t>(jpeg.begin(), jpeg.end()), cv::IMREAD_COLOR);
  EXPECT_LE(std::max(image.cols, image.rows), kBestViewMaxSidePx);
  EXPECT_GE(std::max(image.cols, image.rows), kBestViewMaxSidePx / 2);
  EXPECT_LT(views.bytes(), 8000u);
  // Object 3 left the map (merged or deleted): its view goes, memory with it.
  views.update({square_object(4)}, Frame{}, Pose::Identity());
  EXPECT_TRUE(views.jpeg(3).empty());
  EXPECT_EQ(views.bytes(), 0u);
}

}  // namespace
}  // namespace semap
