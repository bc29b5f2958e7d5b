#include <opencv2/imgcodecs.hpp>

#include "io/image_io.hpp"
#include "io_test_util.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

using test::throws_naming;

cv::Mat gradient_colour(cv::Size size) {
  cv::Mat img(size, CV_8UC3);
  for (int r = 0; r < img.rows; ++r)
    for (int c = 0; c < img.cols; ++c) img.at<cv::Vec3b>(r, c) = cv::Vec3b(uchar(c), uchar(r), uchar(c + r));
  return img;
}

cv::Mat ramp_depth(cv::Size size) {
  cv::Mat d(size, CV_32FC1);
  for (int r = 0; r < d.rows; ++r)
    for (int c = 0; c < d.cols; ++c) d.at<float>(r, c) = 0.5f + 0.01f * c;
  d.at<float>(0, 0) = 0.0f;    // invalid stays invalid
  d.at<float>(0, 1) = 20.0f;   // out of 16-bit range at 5000/m -> invalid
  return d;
}

TEST(ImageIo, ColourDepthLabelRoundTrips) {
  test::TempDir dir;
  const cv::Mat colour = gradient_colour({64, 48});
  write_image(dir / "c.png", colour);
  EXPECT_EQ(cv::norm(read_colour_image(dir / "c.png"), colour, cv::NORM_INF), 0.0);

  const cv::Mat depth = ramp_depth({64, 48});
  write_depth_image(dir / "d.png", depth, 5000.0);
  const cv::Mat back = read_depth_image(dir / "d.png", 5000.0, {64, 48});
  ASSERT_EQ(back.type(), CV_32FC1);
  EXPECT_EQ(back.at<float>(0, 0), 0.0f);
  EXPECT_EQ(back.at<float>(0, 1), 0.0f);
  double max_err = 0;
  for (int r = 1; r < 48; ++r)
    for (int c = 0; c < 64; ++c) max_err = std::max(max_err, double(std::abs(back.at<float>(r, c) - depth.at<float>(r, c))));
  EXPECT_LE(max_err, 0.5 / 5000 + 1e-6);

  cv::Mat labels8(48, 64, CV_8UC1, cv::Scalar(7)), instances(48, 64, CV_16UC1, cv::Scalar(40000));
  write_image(dir / "l.png", labels8);
  write_image(dir / "i.png", instances);
  const cv::Mat l = read_label_image(dir / "l.png"), i = read_label_image(dir / "i.png");
  EXPECT_EQ(l.type(), CV_16UC1);
  EXPECT_EQ(l.at<uint16_t>(5, 5), 7);
  EXPECT_EQ(i.at<uint16_t>(5, 5), 40000);

  // All-zero depth is valid at this level (the pipeline decides what to do with it).
  write_depth_image(dir / "z.png", cv::Mat::zeros(48, 64, CV_32FC1), 5000.0);
  EXPECT_EQ(cv::countNonZero(read_depth_image(dir / "z.png", 5000.0)), 0);

  // Raw 65535 marks invalid depth (7-Scenes).
  write_image(dir / "sat.png", cv::Mat(4, 4, CV_16UC1, cv::Scalar(65535)));
  EXPECT_EQ(cv::countNonZero(read_depth_image(dir / "sat.png", 1000.0)), 0);
}

TEST(ImageIo, BadImagesThrowNamingTheFile) {
  test::TempDir dir;
  const cv::Mat colour = gradient_colour({640, 480});
  write_image(dir / "ok.png", colour);
  write_image(dir / "ok.jpg", colour);
  write_depth_image(dir / "depth.png", ramp_depth({640, 480}), 5000.0);
  const std::string png = test::read_bytes(dir / "ok.png"), jpg = test::read_bytes(dir / "ok.jpg"),
                    depth_png = test::read_bytes(dir / "depth.png");
  for (double keep : {0.05, 0.5, 0.99}) {
    test::write_bytes(dir / "trunc.png", png.substr(0, size_t(png.size() * keep)));
    EXPECT_TRUE(throws_naming([&] { read_colour_image(dir / "trunc.png"); }, "trunc.png")) << keep;
    test::write_bytes(dir / "trunc.jpg", jpg.substr(0, size_t(jpg.size() * keep)));
    EXPECT_TRUE(throws_naming([&] { read_colour_image(dir / "trunc.jpg"); }, "trunc.jpg")) << keep;
    test::write_bytes(dir / "trunc_depth.png", depth_png.substr(0, size_t(depth_png.size() * keep)));
    EXPECT_TRUE(throws_naming([&] { read_depth_image(dir / "trunc_depth.png", 5000); }, "trunc_depth.png"));
  }
  // Corrupt compressed data inside an otherwise complete PNG.
  std::string corrupt = png;
  for (size_t k = corrupt.size() / 3; k < corrupt.size() / 3 + 64; ++k) corrupt[k] = char(~corrupt[k]);
  test::write_bytes(dir / "corrupt.png", corrupt);
  EXPECT_TRUE(throws_naming([&] { read_colour_image(dir / "corrupt.png"); }, "corrupt.png"));
  test::write_bytes(dir / "garbage.png", "this is not an image");
  EXPECT_TRUE(throws_naming([&] { read_colour_image(dir / "garbage.png"); }, "garbage.png"));
  test::write_bytes(dir / "empty.png", "");
  EXPECT_TRUE(throws_naming([&] { read_depth_image(dir / "empty.png", 5000); }, "empty.png"));
  EXPECT_TRUE(throws_naming([&] { read_colour_image(dir / "absent.png"); }, "absent.png"));

  // 8-bit depth, wrong-size depth, colour as depth.
  write_image(dir / "depth8.png", cv::Mat(480, 640, CV_8UC1, cv::Scalar(100)));
  EXPECT_TRUE(throws_naming([&] { read_depth_image(dir / "depth8.png", 5000); }, "depth8.png: 8-bit depth"));
  EXPECT_TRUE(throws_naming([&] { read_depth_image(dir / "depth.png", 5000, {320, 240}); }, "depth.png"));
  EXPECT_TRUE(throws_naming([&] { read_depth_image(dir / "ok.png", 5000); }, "ok.png"));
  EXPECT_TRUE(throws_naming([&] { read_label_image(dir / "ok.png"); }, "ok.png"));
  EXPECT_TRUE(throws_naming([&] { write_image(dir / "noext", colour); }, "noext"));
}

}  // namespace
}  // namespace semap
