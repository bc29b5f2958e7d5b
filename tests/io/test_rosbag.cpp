// ROS1 bag reader (src/io/rosbag_dataset.cpp): bags written here with the rosbag API from
// ../shared/data/tum_fr1_rpy must read back frame for frame like the folder and track to the
// same trajectory; every supported encoding decodes to the known values; broken bags give one
// error line naming the file.
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/dataset.hpp"
#include "io/image_io.hpp"
#include "io_test_util.hpp"
#include "ros_test_messages.hpp"
#include "test_rosbag_writer.hpp"
#include "test_support.hpp"
#include "tracking/tracker.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::BagWriter;
using test::RosCameraInfo;
using test::RosCompressedImage;
using test::RosImage;
using test::RosStamp;
using test::throws_naming;
using namespace test::ros;

constexpr size_t kSliceFrames = 40;  // a short slice: tracking twice stays well under a minute


/// A bag laid out like TUM's own ROS 1 bags.
void write_tum_bag(const DatasetReader& folder, size_t frames, const fs::path& bag_path, bool lz4) {
  BagWriter bag(bag_path, lz4);
  write_tum_frames(bag, folder, frames,
                   {"/camera/rgb/image_color", "/camera/rgb/camera_info", "/camera/depth/image", "/camera/depth/camera_info"});
}


double ms_per_frame(const DatasetReader& reader, size_t frames) {
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < frames; ++i) reader.load(i);
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / frames;
}


class TumBag : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!have_rosbag_support()) return;
    const fs::path root = test::data_dir() / "tum_fr1_rpy";
    if (!fs::exists(root)) return;
    dir_ = std::make_unique<test::TempDir>("semap_rosbag");
    folder_ = open_dataset(root);
    bag_path_ = dir_->path() / "rgbd_dataset_freiburg1_rpy.bag";
    write_tum_bag(*folder_, kSliceFrames, bag_path_, false);
    // TUM publishes the ground truth beside each bag as <name>-groundtruth.txt.
    fs::copy_file(root / "groundtruth.txt", dir_->path() / "rgbd_dataset_freiburg1_rpy-groundtruth.txt");
  }
  static void TearDownTestSuite() {
    folder_.reset();
    dir_.reset();
  }
  void SetUp() override {
    if (!have_rosbag_support()) SEMAP_SKIP_OR_FAIL("built without ROS bag support");
    if (!folder_) SEMAP_SKIP_OR_FAIL("shared data missing: " << test::data_dir() / "tum_fr1_rpy" << " (set SEMAP_DATA_DIR)");
  }
  static std::unique_ptr<test::TempDir> dir_;
  static std::unique_ptr<DatasetReader> folder_;
  static fs::path bag_path_;
};
std::unique_ptr<test::TempDir> TumBag::dir_;
std::unique_ptr<DatasetReader> TumBag::folder_;
fs::path TumBag::bag_path_;

TEST_F(TumBag, ReadsBackFrameForFrameLikeTheFolder) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto bag = open_dataset(bag_path_);
  const double open_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(bag->format(), "rosbag");
  ASSERT_EQ(bag->size(), kSliceFrames);
  EXPECT_EQ(bag->camera().depth, folder_->camera().depth);
  EXPECT_FALSE(bag->camera().has_distortion()) << "the bag's plumb_bob D is undistorted on load";
  EXPECT_FALSE(bag->camera().colour.has_value());
  size_t identical_rgb = 0, identical_depth = 0, same_time = 0, same_gt = 0;
  for (size_t i = 0; i < kSliceFrames; ++i) {
    const Frame a = folder_->load(i), b = bag->load(i);
    identical_rgb += same_pixels(a.rgb, b.rgb);
    identical_depth += same_pixels(a.depth, b.depth);
    same_time += a.timestamp == b.timestamp;
    same_gt += a.gt_T_world_camera && b.gt_T_world_camera && a.gt_T_world_camera->isApprox(*b.gt_T_world_camera, 0);
  }
  EXPECT_EQ(identical_rgb, kSliceFrames);
  EXPECT_EQ(identical_depth, kSliceFrames);
  EXPECT_EQ(same_time, kSliceFrames);
  EXPECT_EQ(same_gt, kSliceFrames);

  // Reading overhead per frame against the PNG folder in the same process (3 rounds, best).
  double folder_ms = 1e9, bag_ms = 1e9;
  for (int round = 0; round < 3; ++round) {
    folder_ms = std::min(folder_ms, ms_per_frame(*folder_, kSliceFrames));
    bag_ms = std::min(bag_ms, ms_per_frame(*bag, kSliceFrames));
  }
  std::cout << "[rosbag] open " << open_ms / kSliceFrames << " ms/frame, load " << bag_ms
            << " ms/frame (TUM folder " << folder_ms << " ms/frame)" << std::endl;
  // Raw messages need no PNG decoding: never much slower than the folder.
  EXPECT_LT(bag_ms, 2.0 * folder_ms + 2.0);
}

TEST_F(TumBag, TracksToTheSameTrajectoryAsTheFolder) {
  const auto bag = open_dataset(bag_path_);
  const Trajectory from_folder = track(*folder_, kSliceFrames), from_bag = track(*bag, kSliceFrames);
  ASSERT_EQ(from_folder.size(), kSliceFrames);
  ASSERT_EQ(from_bag.size(), kSliceFrames);
  size_t identical = 0;
  double max_translation = 0;
  for (size_t i = 0; i < kSliceFrames; ++i) {
    identical += from_folder[i].timestamp == from_bag[i].timestamp &&
                 from_folder[i].T_world_camera.matrix() == from_bag[i].T_world_camera.matrix();
    max_translation = std::max(max_translation, (from_folder[i].T_world_camera.translation() -
                                                 from_bag[i].T_world_camera.translation()).norm());
  }
  const double ate_folder = compute_ate(folder_->ground_truth(), from_folder).rmse;
  const double ate_bag = compute_ate(bag->ground_truth(), from_bag).rmse;
  std::cout << "[rosbag] tracking " << kSliceFrames << " frames: ATE folder " << ate_folder * 100 << " cm, bag "
            << ate_bag * 100 << " cm, " << identical << " identical poses, max position difference "
            << max_translation << " m" << std::endl;
  // Identical inputs, one thread: bit-identical trajectories.
  EXPECT_EQ(identical, kSliceFrames);
  EXPECT_LT(ate_bag, 0.05);  // and a sane one
}

// ------------------------------------------------------------------ encodings

struct EncodingCase {
  std::string name;
  std::string colour;  ///< raw encoding, or "jpeg"/"png" (CompressedImage)
  std::string depth;   ///< 16UC1, 32FC1, 16UC1-be, compressedDepth16, compressedDepth32
};

/// Writes three frames of the small image with the given encodings and reads frame 1 back.
Frame write_and_read(const EncodingCase& c, const SmallFrame& s, const fs::path& dir, CameraModel* camera = nullptr) {
  const fs::path path = dir / (c.name + ".bag");
  {
    BagWriter bag(path, c.name.find("lz4") != std::string::npos);
    for (uint32_t n = 0; n < 3; ++n) {
      const RosStamp t{1000 + n, 5000000};
      if (c.colour == "jpeg" || c.colour == "png") {
        std::vector<uint8_t> bytes;
        cv::imencode("." + c.colour, s.bgr, bytes);
        bag.write(RosCompressedImage{"/cam/color/image_raw/compressed", t, "rgb8; " + c.colour + " compressed bgr8", bytes});
      } else {
        bag.write(colour_message("/cam/color/image_raw", t, s.bgr, c.colour));
      }
      bag.write(info_message("/cam/color/camera_info", t, s.k));
      const RosStamp td{t.sec, t.nsec + 3000000};  // depth 3 ms later, as real drivers do
      if (c.depth.rfind("compressedDepth", 0) == 0) {
        const bool inverse = c.depth == "compressedDepth32";
        bag.write(RosCompressedImage{"/cam/depth/image_raw/compressedDepth", td,
                                     std::string(inverse ? "32FC1" : "16UC1") + "; compressedDepth png",
                                     compressed_depth_bytes(s.depth_m, inverse)});
      } else if (c.depth == "16UC1-be") {
        RosImage m = depth_message("/cam/depth/image_raw", td, s.depth_m, "16UC1");
        for (size_t k = 0; k + 1 < m.data.size(); k += 2) std::swap(m.data[k], m.data[k + 1]);
        m.big_endian = true;
        bag.write(m);
      } else {
        bag.write(depth_message("/cam/depth/image_raw", td, s.depth_m, c.depth));
      }
      bag.write(info_message("/cam/depth/camera_info", td, s.k));
    }
  }
  const auto reader = open_dataset(path);
  EXPECT_EQ(reader->size(), 3u) << c.name;
  if (camera) *camera = reader->camera();
  return reader->load(1);
}


class BagEncodings : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!have_rosbag_support()) SEMAP_SKIP_OR_FAIL("built without ROS bag support");
    SEMAP_REQUIRE_DATA(tum, "tum_fr1_rpy");
    (void)tum;
    small_ = small_frame();
  }
  SmallFrame small_;
  test::TempDir dir_{"semap_rosbag_enc"};
};

TEST_F(BagEncodings, RawColourEncodings) {
  for (const std::string enc : {"rgb8", "bgr8", "rgba8", "mono8"}) {
    CameraModel camera;
    const Frame f = write_and_read({"colour_" + enc, enc, "16UC1"}, small_, dir_.path(), &camera);
    EXPECT_TRUE(same_pixels(f.rgb, enc == "mono8" ? small_.mono_bgr : small_.bgr)) << enc;
    EXPECT_EQ(camera.depth, small_.k) << enc;
    EXPECT_DOUBLE_EQ(f.timestamp, 1001.005) << enc;
  }
}

TEST_F(BagEncodings, RawDepthEncodings) {
  for (const std::string enc : {"16UC1", "32FC1", "16UC1-be"}) {
    const Frame f = write_and_read({"depth_" + enc, "bgr8", enc}, small_, dir_.path());
    ASSERT_EQ(f.depth.size(), small_.depth_m.size()) << enc;
    // 32FC1 carries the floats themselves (NaN -> 0); 16UC1 millimetres convert back within 1 ulp.
    cv::Mat diff;
    cv::absdiff(f.depth, small_.depth_m, diff);
    double max_diff = 0;
    cv::minMaxLoc(diff, nullptr, &max_diff);
    EXPECT_LT(max_diff, enc == "32FC1" ? 1e-12 : 1e-6) << enc;
    EXPECT_EQ(cv::countNonZero(f.depth), cv::countNonZero(small_.depth_m)) << enc;
  }
}

TEST_F(BagEncodings, CompressedColourAndDepth) {
  for (const std::string colour : {"jpeg", "png"}) {
    const Frame f = write_and_read({"compressed_" + colour, colour, "compressedDepth16"}, small_, dir_.path());
    std::vector<uint8_t> bytes;
    cv::imencode("." + colour, small_.bgr, bytes);
    EXPECT_TRUE(same_pixels(f.rgb, cv::imdecode(bytes, cv::IMREAD_COLOR))) << colour;
    EXPECT_LT(mean_abs_diff(f.rgb, small_.bgr), colour == "png" ? 1e-9 : 4.0) << colour;
    cv::Mat diff;
    cv::absdiff(f.depth, small_.depth_m, diff);
    double max_diff = 0;
    cv::minMaxLoc(diff, nullptr, &max_diff);
    EXPECT_LT(max_diff, 1e-6) << "compressedDepth 16UC1 is lossless";
  }
  // 32FC1 compressedDepth quantises inverse depth: error grows with z^2 / depthQuantA.
  const Frame f = write_and_read({"compressed_depth32_lz4", "bgr8", "compressedDepth32"}, small_, dir_.path());
  size_t valid = 0, within = 0;
  for (int r = 0; r < f.depth.rows; ++r)
    for (int c = 0; c < f.depth.cols; ++c) {
      const float z = small_.depth_m.at<float>(r, c), got = f.depth.at<float>(r, c);
      if (z <= 0) continue;
      ++valid;
      within += std::abs(got - z) <= 1.5f * z * z / 10100.0f + 1e-6f;
    }
  EXPECT_GT(valid, 1000u);
  EXPECT_EQ(within, valid);
}

// ------------------------------------------------------------------ topics and errors

TEST_F(BagEncodings, TopicsChosenOrNamed) {
  const fs::path path = dir_ / "two_colour.bag";
  {
    BagWriter bag(path);
    for (uint32_t n = 0; n < 2; ++n) {
      const RosStamp t{2000 + n, 0};
      bag.write(colour_message("/cam/rgb/image_raw", t, small_.bgr, "bgr8"));
      bag.write(colour_message("/cam/rgb/image_rect_color", t, small_.bgr, "rgb8"));
      bag.write(depth_message("/cam/depth/image", t, small_.depth_m, "32FC1"));
      bag.write(info_message("/cam/rgb/camera_info", t, small_.k));
    }
  }
  EXPECT_TRUE(throws_naming([&] { open_dataset(path); }, "several colour image topics (/cam/rgb/image_raw, /cam/rgb/image_rect_color); choose one with --rgb-topic"));
  DatasetOptions options;
  options.rgb_topic = "/cam/rgb/image_rect_color";
  const auto reader = open_dataset(path, options);
  EXPECT_EQ(reader->size(), 2u);
  EXPECT_TRUE(same_pixels(reader->load(0).rgb, small_.bgr));
  EXPECT_EQ(reader->camera().depth, small_.k);  // the only CameraInfo serves both
  options.depth_topic = "/cam/rgb/image_raw";
  EXPECT_TRUE(throws_naming([&] { open_dataset(path, options); }, "/cam/rgb/image_raw has encoding 'bgr8', not a supported depth image"));
  options.depth_topic = "/nowhere";
  EXPECT_TRUE(throws_naming([&] { open_dataset(path, options); }, "no image topic /nowhere"));

  // A raw topic and its /compressed republication are one stream: the raw one is used.
  const fs::path both = dir_ / "raw_and_compressed.bag";
  {
    BagWriter bag(both);
    std::vector<uint8_t> jpeg;
    cv::imencode(".jpg", small_.bgr, jpeg);
    for (uint32_t n = 0; n < 2; ++n) {
      const RosStamp t{3000 + n, 0};
      bag.write(colour_message("/cam/rgb/image_raw", t, small_.bgr, "bgr8"));
      bag.write(RosCompressedImage{"/cam/rgb/image_raw/compressed", t, "bgr8; jpeg compressed bgr8", jpeg});
      bag.write(depth_message("/cam/depth/image", t, small_.depth_m, "16UC1"));
    }
  }
  EXPECT_TRUE(throws_naming([&] { open_dataset(both); }, "no sensor_msgs/CameraInfo"));
}

// The depth CameraInfo's lens distortion is undistorted on load (plumb_bob; TUM's own bags carry
// fr1's); a model semap does not undistort keeps the images (warned); a broken D is one error.
TEST_F(BagEncodings, CameraInfoDistortion) {
  const auto write_bag = [&](const std::string& name, const std::string& model, const std::vector<double>& d) {
    const fs::path path = dir_ / (name + ".bag");
    BagWriter bag(path);
    for (uint32_t n = 0; n < 3; ++n) {
      const RosStamp t{1000 + n, 0};
      bag.write(colour_message("/cam/color/image_raw", t, small_.bgr, "bgr8"));
      bag.write(depth_message("/cam/depth/image_raw", t, small_.depth_m, "16UC1"));
      RosCameraInfo info = info_message("/cam/depth/camera_info", t, small_.k);
      info.D = d;
      info.distortion_model = model;
      bag.write(info);
    }
    return path;
  };
  const auto plumb_bob = open_dataset(write_bag("plumb_bob", "plumb_bob", {0.26, -0.95, -0.005, 0.003, 1.16}));
  EXPECT_FALSE(plumb_bob->camera().has_distortion());
  EXPECT_EQ(plumb_bob->camera().depth, small_.k);
  EXPECT_GT(mean_abs_diff(plumb_bob->load(1).rgb, small_.bgr), 1.0) << "pixels moved by the undistortion";
  const auto fisheye = open_dataset(write_bag("equidistant", "equidistant", {0.1, 0.01, 0, 0}));
  EXPECT_TRUE(same_pixels(fisheye->load(1).rgb, small_.bgr)) << "an unsupported model keeps the images";
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const fs::path broken = write_bag("nan", "plumb_bob", {nan, 0, 0, 0, 0});
  EXPECT_TRUE(throws_naming([&] { open_dataset(broken); }, broken.string() + ": /cam/depth/camera_info: NaN or Inf in D"));
  const fs::path huge = write_bag("huge", "plumb_bob", {50, 0, 0, 0, 0});
  EXPECT_TRUE(throws_naming([&] { open_dataset(huge); }, "distortion coefficient 50"));
}

TEST_F(BagEncodings, CorruptAndTruncatedBags) {
  const fs::path good = dir_ / "good.bag";
  write_and_read({"good", "bgr8", "16UC1"}, small_, dir_.path());
  const std::string bytes = test::read_bytes(good);
  ASSERT_GT(bytes.size(), 1000u);
  const auto one_line_naming = [](const fs::path& path, const std::string& what) {
    expect_one_line_error([&] { open_dataset(path)->load(0); }, path.string(), what, "rosbag");
  };

  test::write_bytes(dir_ / "truncated.bag", bytes.substr(0, bytes.size() / 2));
  one_line_naming(dir_ / "truncated.bag", "bag");
  test::write_bytes(dir_ / "garbage.bag", std::string(4096, 'x'));
  one_line_naming(dir_ / "garbage.bag", "not a ROS bag of format 2.0");
  test::write_bytes(dir_ / "empty.bag", "");
  one_line_naming(dir_ / "empty.bag", "not a ROS bag of format 2.0");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir_ / "absent.bag"); }, "absent.bag: file not found"));
  // A message whose pixels were cut: the record is intact but the image is short.
  const fs::path short_image = dir_ / "short.bag";
  {
    BagWriter bag(short_image);
    RosImage colour = colour_message("/c/image", {1, 0}, small_.bgr, "bgr8");
    colour.data.resize(colour.data.size() / 2);
    bag.write(colour);
    bag.write(depth_message("/d/image", {1, 0}, small_.depth_m, "16UC1"));
    bag.write(info_message("/d/camera_info", {1, 0}, small_.k));
  }
  one_line_naming(short_image, "truncated message");
}

}  // namespace
}  // namespace semap
