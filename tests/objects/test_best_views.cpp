// objects/best_views (issue 43): the view kept per object is its largest unoccluded one, the
// crop shows the object and stays small, and views of objects gone from the map are dropped.
#include <gtest/gtest.h>

#include <cstring>
#include <opencv2/imgcodecs.hpp>

#include "core/archive.hpp"
#include "objects/best_views.hpp"
#include "semap/core/error.hpp"

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

/// Objects 2 and 5, side by side in the image.
std::vector<ObjectInstance> two_objects() {
  ObjectInstance far = square_object(5);
  for (auto& p : far.points) p.x() += 0.6f;
  return {square_object(2), far};
}

/// Views of objects 2 (seen whole, green) and 5 (beside it, grey), kept by one update.
BestViews two_views(const PinholeIntrinsics& camera) {
  BestViews views(camera);
  const std::vector<ObjectInstance> objects = two_objects();
  Frame frame = frame_seeing(camera, cv::Vec3b(0, 200, 0), 0);
  frame.index = 17;
  views.update(objects, frame, Pose::Identity());
  EXPECT_EQ(views.size(), 2u);
  return views;
}

// Issue 43: the views go into map.semap (kObjectViewsSection) and come back byte for byte,
// and the bytes do not depend on the hash order.
TEST(BestViews, SectionRoundTripIsByteIdentical) {
  const PinholeIntrinsics camera = small_camera();
  const BestViews views = two_views(camera);
  const std::string bytes = views.encode(two_objects());
  BestViews loaded(camera);
  loaded.decode(bytes, "m.semap", {2, 5, 9});
  for (const uint32_t id : {2u, 5u}) EXPECT_TRUE(!views.jpeg(id).empty() && loaded.jpeg(id) == views.jpeg(id)) << id;
  EXPECT_EQ(loaded.bytes(), views.bytes());
  EXPECT_TRUE(loaded.encode(two_objects()) == bytes);
  // Only the saved objects' views are written: object 5 gone from the map, its view is not.
  EXPECT_TRUE(views.encode({square_object(2)}) != bytes);
  BestViews without_5(camera);
  EXPECT_THROW(without_5.decode(bytes, "m.semap", {2}), Error);
  without_5.decode(views.encode({square_object(2)}), "m.semap", {2});
  EXPECT_TRUE(without_5.jpeg(2) == views.jpeg(2) && without_5.jpeg(5).empty());
  EXPECT_LT(bytes.size(), views.bytes() + 2 * 40) << "a view costs its JPEG and 28 bytes";
  // The score decides replacement after loading as before: a worse view does not replace.
  loaded.update({square_object(2)}, frame_seeing(camera, cv::Vec3b(0, 0, 255), 80), Pose::Identity());
  EXPECT_TRUE(loaded.jpeg(2) == views.jpeg(2));
}

/// The error of decoding `bytes` as a views section of "bad/map.semap" with objects 2 and 5.
std::string decode_error(const std::string& bytes) {
  BestViews views(small_camera());
  try {
    views.decode(bytes, "bad/map.semap", {2, 5});
  } catch (const Error& e) {
    return e.what();
  }
  return "decoded";
}

// A corrupt section is one error naming the file and the section; nothing is allocated for a
// size the bytes do not hold.
TEST(BestViews, BadSectionIsOneErrorNamingTheFile) {
  const std::string good = two_views(small_camera()).encode(two_objects());
  auto with = [&](size_t offset, auto value) {
    std::string b = good;
    std::memcpy(b.data() + offset, &value, sizeof value);
    return b;
  };
  const size_t first_view = 4 + 8, first_size = first_view + 4 + 8 + 8;
  struct Case {
    std::string what, bytes, says;
  };
  const std::vector<Case> cases = {
      {"truncated", good.substr(0, good.size() - 3), "truncated"},
      {"format", with(0, uint32_t{9}), "format 9"},
      {"count", with(4, uint64_t{1} << 40), "a count of"},
      {"unknown object", with(first_view, uint32_t{4}), "object 4, which the object map does not hold"},
      {"not ascending", with(first_view, uint32_t{5}), "not ascending"},
      {"score", with(first_view + 4, -1.0), "score"},
      {"huge view", with(first_size, uint64_t{1} << 30), "at most"},
      {"over the limit", with(first_size, uint64_t{kBestViewMaxJpegBytes + 1}), "at most"},
      {"not a JPEG", with(first_size + 8, uint16_t{0x4b50}), "not a JPEG"},
      {"trailing bytes", good + "x", "unexpected bytes"},
  };
  for (const auto& [what, bytes, says] : cases) {
    const std::string e = decode_error(bytes);
    EXPECT_NE(e.find("bad/map.semap"), std::string::npos) << what << ": " << e;
    EXPECT_NE(e.find(kObjectViewsSection), std::string::npos) << what << ": " << e;
    EXPECT_NE(e.find(says), std::string::npos) << what << ": " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << what << ": " << e;
  }
}

// Map merging: the other map's views follow its objects' new ids; where both saw an object, the
// better view stays.
TEST(BestViews, MergeFollowsTheNewIdsAndKeepsTheBetterView) {
  const PinholeIntrinsics camera = small_camera();
  const BestViews other = two_views(camera);  // objects 2 (whole) and 5
  BestViews here(camera);
  here.update({square_object(1)}, frame_seeing(camera, cv::Vec3b(0, 0, 255), 80), Pose::Identity());
  ObjectInstance half_seen = square_object(8);
  here.update({square_object(1), half_seen}, frame_seeing(camera, cv::Vec3b(0, 0, 255), 80), Pose::Identity());
  const std::string own_view_of_8 = here.jpeg(8);
  ASSERT_FALSE(own_view_of_8.empty());
  // Other's 2 folded into our 1 (ours was half hidden: other's whole view wins); other's 5 is
  // new here as 12.
  here.merge(other, {{2, 1}, {5, 12}});
  EXPECT_TRUE(here.jpeg(1) == other.jpeg(2));
  EXPECT_TRUE(here.jpeg(12) == other.jpeg(5));
  EXPECT_TRUE(here.jpeg(8) == own_view_of_8) << "untouched by the merge";
  // The other way round: a half-hidden view folded into a whole one leaves the whole one.
  BestViews whole = two_views(camera);
  BestViews half(camera);
  half.update({square_object(3)}, frame_seeing(camera, cv::Vec3b(0, 0, 255), 80), Pose::Identity());
  whole.merge(half, {{3, 2}});
  EXPECT_TRUE(whole.jpeg(2) == other.jpeg(2));
}

}  // namespace
}  // namespace semap
