// Issue 44, classes 1-3 (readers): ROS1 bags are checked before librosbag sees them
// (src/io/rosbag_validate.cpp), messages are read with checked array lengths
// (src/io/rosbag_backend.cpp), and every reader's camera goes through the same check
// (DatasetReader::set_camera). Inputs are made here: small bags from the rosbag writer, then
// corrupted; a .sens header written byte by byte. Each case must end in one semap::Error line
// naming the file, never a signal, a silent success or a large allocation.
#include <cstring>
#include <opencv2/core.hpp>

#include "io_test_util.hpp"
#include "ros_test_messages.hpp"
#include "semap/io/dataset.hpp"
#include "test_rosbag_writer.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::BagWriter;
using test::RosCameraInfo;
using test::throws_naming;
using namespace test::ros;

constexpr int kWidth = 32, kHeight = 24;
constexpr uint32_t kFrames = 6;

PinholeIntrinsics small_camera(int width = kWidth, int height = kHeight) {
  return {30.0 * width / kWidth, 30.0 * width / kWidth, width / 2.0 - 0.5, height / 2.0 - 0.5, width, height};
}

/// A bag of `frames` synthetic colour + depth frames; `colour_info`: the colour topic has its
/// own CameraInfo; `info_sizes`: the CameraInfos give their image size (0x0 otherwise, as some
/// drivers write).
void write_bag(const fs::path& path, bool lz4, int colour_width = kWidth, bool colour_info = true,
               uint32_t frames = kFrames, bool info_sizes = true) {
  BagWriter bag(path, lz4);
  cv::RNG rng(7);
  const int colour_height = colour_width * kHeight / kWidth;
  const auto info = [&](const std::string& topic, uint32_t n, int width, int height) {
    RosCameraInfo m = info_message(topic, {n + 1, 0}, small_camera(width, height));
    if (!info_sizes) m.width = m.height = 0;
    return m;
  };
  for (uint32_t n = 0; n < frames; ++n) {
    cv::Mat bgr(colour_height, colour_width, CV_8UC3), depth(kHeight, kWidth, CV_32FC1);
    rng.fill(bgr, cv::RNG::UNIFORM, 0, 255);
    rng.fill(depth, cv::RNG::UNIFORM, 0.5, 3.0);
    bag.write(colour_message("/c/image", {n + 1, 0}, bgr, "bgr8"));
    bag.write(depth_message("/d/image", {n + 1, 0}, depth, "32FC1"));
    bag.write(info("/d/camera_info", n, kWidth, kHeight));
    if (colour_info) bag.write(info("/c/camera_info", n, colour_width, colour_height));
  }
}

uint32_t u32_at(const std::string& bytes, size_t pos) {
  uint32_t v = 0;
  std::memcpy(&v, bytes.data() + pos, 4);
  return v;
}
void set_u32(std::string& bytes, size_t pos, uint32_t v) { std::memcpy(bytes.data() + pos, &v, 4); }

/// Opens the bag and reads every frame; returns "" when that worked, else the one error line
/// (a non-semap exception fails the test).
std::string open_and_read(const fs::path& path) {
  try {
    const auto reader = open_dataset(path);
    for (size_t i = 0; i < reader->size(); ++i) reader->load(i);
    return "";
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << path << ": non-semap exception: " << e.what();
    return "non-semap exception";
  }
}

class BagBounds : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!have_rosbag_support()) GTEST_SKIP() << "built without ROS bag support";
    good_ = dir_.path() / "good.bag";
    write_bag(good_, false);
    bytes_ = test::read_bytes(good_);
  }
  /// The bytes with one change, written to a new bag; returns its path.
  fs::path mutated(const std::string& name, const std::string& bytes) {
    const fs::path p = dir_.path() / name;
    test::write_bytes(p, bytes);
    return p;
  }
  test::TempDir dir_{"semap_bag_bounds"};
  fs::path good_;
  std::string bytes_;
};

TEST_F(BagBounds, ValidBagsStillReadFrameForFrame) {
  for (const bool lz4 : {false, true}) {
    const fs::path path = dir_.path() / (lz4 ? "lz4.bag" : "plain.bag");
    write_bag(path, lz4);
    const auto reader = open_dataset(path);
    ASSERT_EQ(reader->size(), kFrames) << path;
    EXPECT_EQ(reader->load(kFrames - 1).rgb.cols, kWidth);
  }
}

// Every 32-bit field of the bag's headers that holds a length or an offset (a value under the
// file size) made to point past its record, its chunk and the file, or one byte off: each bag
// must either read or fail with one line naming it. Without the pre-pass librosbag crashes
// (signal) on many of these or reads past its buffer.
TEST_F(BagBounds, EveryLengthAndOffsetPointingElsewhereIsOneErrorLine) {
  const fs::path small = dir_.path() / "small.bag";  // two frames: the sweep stays a few seconds
  write_bag(small, false, kWidth, true, 2);
  const std::string original = test::read_bytes(small);
  size_t mutations = 0, errors = 0;
  const uint32_t size = static_cast<uint32_t>(original.size());
  for (size_t pos = 13; pos + 4 <= original.size(); ++pos) {
    const uint32_t v = u32_at(original, pos);
    if (v == 0 || v >= size) continue;
    for (const uint32_t changed : {v + 1, 0xFFFFFFF0u}) {
      std::string bytes = original;
      set_u32(bytes, pos, changed);
      const fs::path bag = mutated("mutated.bag", bytes);
      const std::string error = open_and_read(bag);
      ++mutations;
      if (error.empty()) continue;
      ++errors;
      ASSERT_EQ(error.find('\n'), std::string::npos) << error;
      ASSERT_NE(error.find(bag.string()), std::string::npos) << "at byte " << pos << ": " << error;
    }
    if (::testing::Test::HasFatalFailure()) return;
  }
  std::cout << "[bag bounds] " << mutations << " mutated bags, " << errors << " rejected with one line" << std::endl;
  EXPECT_GT(errors, mutations / 10);  // most of them are corrupt: the sweep really reached the parser
}

/// Byte position of the first message record's header field "name=" in an uncompressed bag.
size_t field_value_at(const std::string& bytes, const std::string& name, size_t from = 0) {
  const size_t at = bytes.find(name + "=", from);
  EXPECT_NE(at, std::string::npos) << name;
  return at + name.size() + 1;
}

/// A top-level record of a bag (test-side walk: header length, header, data length, data).
struct TopRecord {
  size_t offset = 0, data_offset = 0;
  uint8_t op = 0;
};
std::vector<TopRecord> top_level_records(const std::string& bytes) {
  std::vector<TopRecord> out;
  for (size_t pos = 13; pos + 8 <= bytes.size();) {
    const uint32_t header = u32_at(bytes, pos);
    const size_t op = bytes.find("op=", pos + 4);
    TopRecord r{pos, pos + 8 + header, static_cast<uint8_t>(bytes[op + 3])};
    out.push_back(r);
    pos = r.data_offset + u32_at(bytes, pos + 4 + header);
  }
  return out;
}

TEST_F(BagBounds, IndexEntryOutsideItsChunkIsNamed) {
  // The first index record (op 4): 12-byte entries (time, offset into the uncompressed chunk).
  for (const TopRecord& r : top_level_records(bytes_)) {
    if (r.op != 0x04) continue;
    for (const uint32_t offset : {0x00FFFFF0u, u32_at(bytes_, r.data_offset + 8) + 1}) {
      std::string bytes = bytes_;
      set_u32(bytes, r.data_offset + 8, offset);
      const fs::path bag = mutated("index_outside.bag", bytes);
      const std::string error = open_and_read(bag);
      EXPECT_NE(error.find(bag.string() + ": corrupt ROS bag: index entry points to offset " + std::to_string(offset)),
                std::string::npos) << error;
    }
    return;
  }
  FAIL() << "no index record in the bag";
}

TEST_F(BagBounds, CameraInfoArrayLengthThatWrapsIsRejectedBeforeAllocating) {
  // D of the first CameraInfo message: "plumb_bob" (distortion_model) then the element count 5
  // (the connection's message definition mentions plumb_bob too).
  size_t model = bytes_.find("plumb_bob");
  while (model != std::string::npos && u32_at(bytes_, model + 9) != 5u) model = bytes_.find("plumb_bob", model + 1);
  ASSERT_NE(model, std::string::npos);
  std::string bytes = bytes_;
  set_u32(bytes, model + 9, 0x20000001u);  // 8 x count wraps to 8 bytes in 32 bits
  const fs::path bag = mutated("wrapping_d.bag", bytes);
  const std::string error = open_and_read(bag);
  EXPECT_NE(error.find(bag.string()), std::string::npos) << error;
  EXPECT_NE(error.find("array of 536870913 elements overruns its message"), std::string::npos) << error;
}

TEST_F(BagBounds, ImageArrayLengthOverItsMessageIsRejected) {
  const size_t encoding = bytes_.find("bgr8");
  ASSERT_NE(encoding, std::string::npos);
  // bgr8, is_bigendian (1 byte), step (4), then the pixel count.
  const size_t count_at = encoding + 4 + 1 + 4;
  ASSERT_EQ(u32_at(bytes_, count_at), uint32_t(kWidth * kHeight * 3));
  std::string bytes = bytes_;
  set_u32(bytes, count_at, 0xFFFFFFF0u);
  const fs::path bag = mutated("huge_image.bag", bytes);
  const std::string error = open_and_read(bag);
  EXPECT_NE(error.find(bag.string()), std::string::npos) << error;
  EXPECT_NE(error.find("overruns its message"), std::string::npos) << error;
}

TEST_F(BagBounds, ChunkDeclaringMoreThanTheLimitIsRejected) {
  const size_t size_at = field_value_at(bytes_, "size");
  std::string bytes = bytes_;
  set_u32(bytes, size_at, 0xFFFFFFFFu);
  const fs::path bag = mutated("huge_chunk.bag", bytes);
  EXPECT_NE(open_and_read(bag).find(bag.string() + ": corrupt ROS bag: chunk of 4294967295 bytes"), std::string::npos)
      << open_and_read(bag);
}

TEST_F(BagBounds, ColourWithoutCameraInfoAtAnotherResolutionIsAnError) {
  // With and without a size in the depth CameraInfo (without one, the colour images used to get
  // the depth intrinsics at their own resolution: wrong colours, exit 0).
  for (const bool info_sizes : {true, false}) {
    const fs::path bag = dir_.path() / (info_sizes ? "colour_no_info.bag" : "colour_no_info_no_size.bag");
    write_bag(bag, false, 2 * kWidth, false, kFrames, info_sizes);
    EXPECT_TRUE(throws_naming([&] { open_dataset(bag); },
                              bag.string() + ": only /d/camera_info describes both /c/image (64x48) and /d/image (32x24)"));
  }
  // At the depth resolution the colour camera is registered to depth: it reads.
  const fs::path same = dir_.path() / "colour_same_size.bag";
  write_bag(same, false, kWidth, false);
  EXPECT_EQ(open_dataset(same)->size(), kFrames);
}

TEST_F(BagBounds, CameraInfoWithImplausibleIntrinsicsGoesThroughTheCameraCheck) {
  const fs::path bag = dir_.path() / "principal_point.bag";
  {
    BagWriter w(bag);
    PinholeIntrinsics k = small_camera();
    k.cx = -5000;
    w.write(colour_message("/c/image", {1, 0}, cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(1, 2, 3)), "bgr8"));
    w.write(depth_message("/d/image", {1, 0}, cv::Mat(kHeight, kWidth, CV_32FC1, cv::Scalar(1.0f)), "32FC1"));
    w.write(info_message("/d/camera_info", {1, 0}, k));
  }
  EXPECT_TRUE(throws_naming([&] { open_dataset(bag); }, bag.string() + ": camera cx = -5000 is outside the image"));
}

// ------------------------------------------------------------------ .sens camera (class 3)

/// A ScanNet .sens v4 header with the given depth = colour intrinsics and size, and no frames.
std::string sens_header(double fx, double cx, uint32_t width, uint32_t height) {
  std::string out;
  const auto put = [&out](const auto& v) { out.append(reinterpret_cast<const char*>(&v), sizeof v); };
  put(uint32_t{4});
  put(uint64_t{4});
  out += "test";
  const auto matrix = [&](const std::array<float, 16>& m) { for (float v : m) put(v); };
  const std::array<float, 16> k{float(fx), 0, float(cx), 0, 0, float(fx), float(height / 2.0), 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const std::array<float, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  matrix(k), matrix(identity), matrix(k), matrix(identity);
  put(int32_t{2}), put(int32_t{1});  // JPEG colour, zlib depth
  put(width), put(height), put(width), put(height);
  put(1000.0f);
  put(uint64_t{0});
  return out;
}

TEST(SensCamera, ImplausibleIntrinsicsAreRejectedLikeEveryReader) {
  test::TempDir dir("semap_sens_camera");
  const auto check = [&](const std::string& name, const std::string& bytes, const std::string& must_name) {
    const fs::path file = dir.path() / name;
    test::write_bytes(file, bytes);
    EXPECT_TRUE(throws_naming([&] { open_dataset(file); }, file.string() + ": " + must_name)) << name;
  };
  check("tiny_focal.sens", sens_header(3, 320, 640, 480), "camera fx = 3 is outside");
  check("centre_outside.sens", sens_header(500, -5000, 640, 480), "camera cx = -5000 is outside the image");
  check("huge.sens", sens_header(8000, 8192, 16384, 16384), "camera width x height = 2.68435e+08 pixels");
  // The same header with plausible values passes the camera check and stops at its 0 frames.
  check("plausible.sens", sens_header(500, 320, 640, 480), "dataset has no frames");
}

}  // namespace
}  // namespace semap
