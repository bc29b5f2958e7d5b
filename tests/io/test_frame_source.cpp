// FrameSource over datasets (src/io/frame_source.cpp): the frames of the reader in order, a
// stop from another thread, and an unreadable frame that is reported and stepped over.
#include <thread>

#include "semap/io/frame_source.hpp"
#include "io/image_io.hpp"
#include "io_test_util.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;

bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST(FrameSource, DatasetFramesInOrder) {
  SEMAP_REQUIRE_DATA(root, "tum_fr1_rpy");
  const auto reader = open_dataset(root);
  const auto source = open_frame_source(root.string());
  EXPECT_FALSE(source->is_live());
  EXPECT_EQ(source->size_hint(), reader->size());
  ASSERT_NE(source->dataset(), nullptr);
  EXPECT_EQ(source->dataset()->format(), "tum");
  EXPECT_EQ(source->camera().depth, reader->camera().depth);
  size_t same = 0;
  for (size_t i = 0; i < 10; ++i) {
    const auto frame = source->next();
    ASSERT_TRUE(frame.has_value());
    const Frame expected = reader->load(i);
    same += frame->index == i && frame->timestamp == expected.timestamp && same_pixels(frame->rgb, expected.rgb) &&
            same_pixels(frame->depth, expected.depth);
  }
  EXPECT_EQ(same, 10u);
  std::thread([&] { source->request_stop(); }).join();
  EXPECT_FALSE(source->next().has_value());
  EXPECT_FALSE(source->next().has_value());
}

TEST(FrameSource, EndAndUnreadableFrame) {
  test::TempDir tmp;
  const fs::path dir = tmp / "rgbd_dataset_freiburg1_tiny";
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::string rgb, depth;
  for (int i = 0; i < 4; ++i) {
    const std::string stamp = std::to_string(100 + i) + ".000000";
    write_image(dir / "rgb" / (stamp + ".png"), cv::Mat(480, 640, CV_8UC3, cv::Scalar(i, 2 * i, 3 * i)));
    write_depth_image(dir / "depth" / (stamp + ".png"), cv::Mat(480, 640, CV_32FC1, cv::Scalar(1.5)), 5000.0);
    rgb += stamp + " rgb/" + stamp + ".png\n";
    depth += stamp + " depth/" + stamp + ".png\n";
  }
  test::write_text(dir / "rgb.txt", rgb);
  test::write_text(dir / "depth.txt", depth);
  const fs::path broken = dir / "rgb" / "102.000000.png";
  const std::string bytes = test::read_bytes(broken);
  test::write_bytes(broken, bytes.substr(0, bytes.size() / 2));

  const auto source = open_frame_source(dir.string());
  EXPECT_EQ(source->next()->index, 0u);
  EXPECT_EQ(source->next()->index, 1u);
  EXPECT_TRUE(test::throws_naming([&] { source->next(); }, "102.000000.png: truncated PNG"));
  EXPECT_EQ(source->next()->index, 3u);  // the unreadable frame was stepped over
  EXPECT_FALSE(source->next().has_value());
  EXPECT_TRUE(test::throws_naming([&] { open_frame_source((tmp / "absent").string()); }, "dataset folder not found"));
}

}  // namespace
}  // namespace semap
