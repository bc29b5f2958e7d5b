// rosbag2 reader (issue 40: src/io/rosbag2_*.cpp, mcap_reader.cpp, cdr_reader.cpp): a TUM
// slice written here as rosbag2 in both storages (SQLite3 of Humble and Jazzy, split into
// several files; MCAP with zstd, lz4 and uncompressed chunks, with and without summary,
// unchunked) reads back frame for frame like the folder and maps to the same trajectory;
// the encodings decode to the known values; every bad-input case of the issue is one error
// line naming the file.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <iostream>

#include "semap/io/dataset.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "core/progress.hpp"
#include "io/cdr_reader.hpp"
#include "io/image_io.hpp"
#include "io/mcap_reader.hpp"
#include "io_test_util.hpp"
#include "ros_test_messages.hpp"
#include "rosbag2_writer.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::McapCompression;
using test::Rosbag2Storage;
using test::Rosbag2Writer;
using test::Rosbag2WriterOptions;
using test::RosCompressedImage;
using test::RosImage;
using test::RosStamp;
using namespace test::ros;

constexpr size_t kSliceFrames = 6;  // geometry of a few frames: the bags are written 6 times

struct Variant {
  std::string name;  ///< folder, or file name with its extension
  Rosbag2WriterOptions options;
};

std::vector<Variant> variants() {
  using S = Rosbag2Storage;
  using C = McapCompression;
  return {
      {"humble_split", {S::sqlite_humble, C::none, true, true, 1 << 20, 10}},  // 3 .db3 files + metadata.yaml
      {"jazzy.db3", {S::sqlite_jazzy, C::none, true, true, 1 << 20, 0}},
      {"mcap_zstd", {S::mcap, C::zstd, true, true, 1 << 20, 0}},               // several chunks, summary
      {"lz4_no_summary.mcap", {S::mcap, C::lz4, true, false, 1 << 20, 0}},     // linear scan
      {"mcap_uncompressed_split", {S::mcap, C::none, true, true, 3 << 20, 12}},
      {"unchunked.mcap", {S::mcap, C::none, false, true, 1 << 20, 0}},
  };
}

/// The slice with the ROS 2 camera drivers' topic names.
void write_tum_bag(const DatasetReader& folder, const Variant& v, const fs::path& path) {
  Rosbag2Writer bag(path, v.options);
  write_tum_frames(bag, folder, kSliceFrames,
                   {"/camera/color/image_raw", "/camera/color/camera_info", "/camera/depth/image_raw",
                    "/camera/depth/camera_info"});
}

class TumRosbag2 : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const fs::path root = test::data_dir() / "tum_fr1_rpy";
    if (!fs::exists(root)) return;
    dir_ = std::make_unique<test::TempDir>("semap_rosbag2");
    folder_ = open_dataset(root);
    for (const Variant& v : variants()) write_tum_bag(*folder_, v, dir_->path() / v.name);
  }
  static void TearDownTestSuite() {
    folder_.reset();
    dir_.reset();
  }
  void SetUp() override {
    if (!folder_) SEMAP_SKIP_OR_FAIL("shared data missing: " << test::data_dir() / "tum_fr1_rpy" << " (set SEMAP_DATA_DIR)");
  }
  static std::unique_ptr<test::TempDir> dir_;
  static std::unique_ptr<DatasetReader> folder_;
};
std::unique_ptr<test::TempDir> TumRosbag2::dir_;
std::unique_ptr<DatasetReader> TumRosbag2::folder_;

TEST_F(TumRosbag2, EveryStorageReadsBackFrameForFrameLikeTheFolder) {
  for (const Variant& v : variants()) {
    const fs::path path = dir_->path() / v.name;
    const auto t0 = std::chrono::steady_clock::now();
    const auto bag = open_dataset(path);
    const double open_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(bag->format(), "rosbag2") << v.name;
    ASSERT_EQ(bag->size(), kSliceFrames) << v.name;
    EXPECT_EQ(bag->camera().depth, folder_->camera().depth) << v.name;
    EXPECT_FALSE(bag->camera().has_distortion()) << v.name << ": the plumb_bob D is undistorted on load";
    size_t identical_rgb = 0, identical_depth = 0, same_time = 0;
    for (size_t i = 0; i < kSliceFrames; ++i) {
      const Frame a = folder_->load(i), b = bag->load(i);
      identical_rgb += same_pixels(a.rgb, b.rgb);
      identical_depth += same_pixels(a.depth, b.depth);
      same_time += a.timestamp == b.timestamp;
    }
    const auto t1 = std::chrono::steady_clock::now();
    for (size_t i = 0; i < kSliceFrames; ++i) bag->load(i);
    std::cout << "[rosbag2] " << v.name << ": open " << open_ms / kSliceFrames << " ms/frame, load "
              << std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count() / kSliceFrames
              << " ms/frame" << std::endl;
    EXPECT_EQ(identical_rgb, kSliceFrames) << v.name;
    EXPECT_EQ(identical_depth, kSliceFrames) << v.name;
    EXPECT_EQ(same_time, kSliceFrames) << v.name;
  }
  EXPECT_TRUE(fs::exists(dir_->path() / "humble_split" / "humble_split_2.db3")) << "the split bag has 3 files";
  EXPECT_EQ(open_dataset(dir_->path() / "humble_split" / "metadata.yaml")->size(), kSliceFrames) << "its metadata.yaml names it too";
}

TEST_F(TumRosbag2, McapIsReadThroughItsSummaryOrByScanning) {
  const auto count = [](const fs::path& file, bool* summary) {
    io_detail::McapReader mcap(file);
    *summary = mcap.read_through_summary();
    return mcap.messages().size();
  };
  bool summary = false;
  EXPECT_EQ(count(dir_->path() / "mcap_zstd" / "mcap_zstd_0.mcap", &summary), 5 * kSliceFrames);
  EXPECT_TRUE(summary);
  EXPECT_EQ(count(dir_->path() / "lz4_no_summary.mcap", &summary), 5 * kSliceFrames);
  EXPECT_FALSE(summary);
  // A damaged summary (a chunk index pointing elsewhere): warned, the scan finds every message.
  std::string bytes = test::read_bytes(dir_->path() / "mcap_zstd" / "mcap_zstd_0.mcap");
  uint64_t summary_start = 0;  // the footer's first field; the footer is the 29 bytes before the end magic
  std::memcpy(&summary_start, bytes.data() + bytes.size() - 8 - 29 + 9, 8);
  const size_t first_chunk_index = bytes.find('\x08', summary_start);
  ASSERT_NE(first_chunk_index, std::string::npos);
  bytes[first_chunk_index + 9 + 16] ^= 0x40;  // chunk_start_offset
  const fs::path damaged = dir_->path() / "damaged_summary.mcap";
  test::write_bytes(damaged, bytes);
  EXPECT_EQ(count(damaged, &summary), 5 * kSliceFrames);
  EXPECT_FALSE(summary);
}

TEST_F(TumRosbag2, MapsToTheSameTrajectoryAsTheFolder) {
  // `semap run` (run_pipeline) with pipeline.threads 1, geometry only: identical inputs give a
  // byte-identical trajectory.txt and mesh.ply.
  Progress::set_mode(-1);
  const auto map = [&](const fs::path& dataset, const std::string& name) {
    RunOptions o;
    o.dataset = dataset;
    o.out_dir = dir_->path() / ("out_" + name);
    o.segmenter = "none";
    o.max_frames = kSliceFrames;
    o.evaluate = false;
    o.show_progress = false;
    SemapConfig config;
    config.pipeline.threads = 1;
    run_pipeline(o, config);
    return std::make_pair(test::read_bytes(o.out_dir / "trajectory.txt"), test::read_bytes(o.out_dir / "mesh.ply"));
  };
  const auto folder = map(test::data_dir() / "tum_fr1_rpy", "folder");
  ASSERT_FALSE(folder.first.empty());
  EXPECT_EQ(std::count(folder.first.begin(), folder.first.end(), '\n'), static_cast<long>(kSliceFrames + 1)) << "header + one pose a frame";
  for (const std::string name : {"humble_split", "mcap_zstd"}) {
    const auto bag = map(dir_->path() / name, name);
    EXPECT_EQ(bag.first, folder.first) << name << ": trajectory.txt differs from the folder's";
    EXPECT_TRUE(bag.second == folder.second) << name << ": mesh.ply differs from the folder's";
  }
}

// ------------------------------------------------------------------ encodings and topics

class Rosbag2Small : public ::testing::Test {
 protected:
  void SetUp() override {
    SEMAP_REQUIRE_DATA(tum, "tum_fr1_rpy");
    (void)tum;
    small_ = small_frame();
  }
  /// Three frames of the small image, colour as `colour` (raw encoding, or jpeg/png), depth as
  /// 16UC1 / 32FC1 / compressedDepth16 / compressedDepth32; `patch` edits each message.
  fs::path write(const std::string& name, const std::string& colour, const std::string& depth,
                 Rosbag2WriterOptions options = {}) {
    const fs::path path = dir_.path() / name;
    Rosbag2Writer bag(path, options);
    for (uint32_t n = 0; n < 3; ++n) {
      const RosStamp t{1000 + n, 5000000};
      if (colour == "jpeg" || colour == "png") {
        std::vector<uint8_t> bytes;
        cv::imencode("." + colour, small_.bgr, bytes);
        bag.write(RosCompressedImage{"/cam/color/image_raw/compressed", t, "rgb8; " + colour + " compressed bgr8", bytes});
      } else {
        bag.write(colour_message("/cam/color/image_raw", t, small_.bgr, colour));
      }
      bag.write(info_message("/cam/color/camera_info", t, small_.k));
      const RosStamp td{t.sec, t.nsec + 3000000};
      if (depth.rfind("compressedDepth", 0) == 0) {
        const bool inverse = depth == "compressedDepth32";
        bag.write(RosCompressedImage{"/cam/depth/image_raw/compressedDepth", td,
                                     std::string(inverse ? "32FC1" : "16UC1") + "; compressedDepth png",
                                     compressed_depth_bytes(small_.depth_m, inverse)});
      } else {
        bag.write(depth_message("/cam/depth/image_raw", td, small_.depth_m, depth));
      }
      bag.write(info_message("/cam/depth/camera_info", td, small_.k));
    }
    return path;
  }
  template <class F>
  static void expect_error(F&& fn, const fs::path& file, const std::string& what) {
    expect_one_line_error(std::forward<F>(fn), file.string(), what, "rosbag2");
  }
  void expect_open_error(const fs::path& path, const fs::path& file, const std::string& what) {
    expect_error([&] { open_dataset(path)->load(0); }, file, what);
  }
  SmallFrame small_;
  test::TempDir dir_{"semap_rosbag2_small"};
};

TEST_F(Rosbag2Small, EveryEncodingDecodes) {
  for (const std::string enc : {"rgb8", "bgr8", "rgba8", "mono8"}) {
    const auto bag = open_dataset(write("colour_" + enc + ".mcap", enc, "16UC1"));
    ASSERT_EQ(bag->size(), 3u) << enc;
    const Frame f = bag->load(1);
    EXPECT_TRUE(same_pixels(f.rgb, enc == "mono8" ? small_.mono_bgr : small_.bgr)) << enc;
    EXPECT_EQ(bag->camera().depth, small_.k) << enc;
    EXPECT_DOUBLE_EQ(f.timestamp, 1001.005) << enc;
  }
  for (const std::string depth : {"16UC1", "32FC1", "compressedDepth16", "compressedDepth32"}) {
    const Frame f = open_dataset(write("depth_" + depth + ".mcap", "bgr8", depth))->load(1);
    size_t valid = 0, within = 0;
    for (int r = 0; r < f.depth.rows; ++r)
      for (int c = 0; c < f.depth.cols; ++c) {
        const float z = small_.depth_m.at<float>(r, c), got = f.depth.at<float>(r, c);
        if (z <= 0) continue;
        ++valid;
        // 32FC1 compressedDepth quantises inverse depth (error ~ z^2 / depthQuantA); the rest is exact to 1 ulp.
        within += std::abs(got - z) <= (depth == "compressedDepth32" ? 1.5f * z * z / 10100.0f + 1e-6f : 1e-6f);
      }
    EXPECT_GT(valid, 1000u) << depth;
    EXPECT_EQ(within, valid) << depth;
  }
  for (const std::string colour : {"jpeg", "png"}) {
    const Frame f = open_dataset(write("compressed_" + colour + ".db3", colour, "16UC1",
                                       {Rosbag2Storage::sqlite_humble}))->load(1);
    std::vector<uint8_t> bytes;
    cv::imencode("." + colour, small_.bgr, bytes);
    EXPECT_TRUE(same_pixels(f.rgb, cv::imdecode(bytes, cv::IMREAD_COLOR))) << colour;
  }
}

TEST_F(Rosbag2Small, TopicsChosenOrNamed) {
  const fs::path path = dir_.path() / "two_colour.mcap";
  {
    Rosbag2Writer bag(path, {});
    for (uint32_t n = 0; n < 2; ++n) {
      const RosStamp t{2000 + n, 0};
      bag.write(colour_message("/cam/rgb/image_raw", t, small_.bgr, "bgr8"));
      bag.write(colour_message("/cam/rgb/image_rect_color", t, small_.bgr, "rgb8"));
      bag.write(depth_message("/cam/depth/image", t, small_.depth_m, "32FC1"));
      bag.write(info_message("/cam/rgb/camera_info", t, small_.k));
    }
  }
  EXPECT_TRUE(test::throws_naming([&] { open_dataset(path); }, "several colour image topics (/cam/rgb/image_raw, /cam/rgb/image_rect_color); choose one with --rgb-topic"));
  DatasetOptions options;
  options.rgb_topic = "/cam/rgb/image_rect_color";
  const auto reader = open_dataset(path, options);
  EXPECT_EQ(reader->size(), 2u);
  EXPECT_TRUE(same_pixels(reader->load(0).rgb, small_.bgr));
}

/// Big-endian CDR (encapsulation 00 00) with its alignment counted from after the 4-byte
/// header: CompressedImage {stamp 7.5 s, frame_id "a", format "jpeg", data 1 2 3}.
TEST(Cdr, BigEndianAndAlignment) {
  const std::vector<uint8_t> message = {0, 0, 0, 0,                 // encapsulation: CDR_BE
                                        0, 0, 0, 7, 0x1d, 0xcd, 0x65, 0,  // sec 7, nanosec 500000000
                                        0, 0, 0, 2, 'a', 0, 0, 0,         // frame_id "a", 2 bytes padding
                                        0, 0, 0, 5, 'j', 'p', 'e', 'g', 0, 0, 0, 0,  // format, 3 padding
                                        0, 0, 0, 3, 1, 2, 3};             // data
  const auto image = io_detail::ros2_msgs::compressed_image(message, "be.cdr");
  EXPECT_EQ(image.format, "jpeg");
  EXPECT_EQ(image.data, (std::vector<uint8_t>{1, 2, 3}));
  const auto meta = io_detail::ros2_msgs::image_meta(message, true, "be.cdr");
  EXPECT_EQ(meta.header_stamp.sec, 7u);
  EXPECT_EQ(meta.header_stamp.nsec, 500000000u);
  // The same CameraInfo through the writer (little endian): D's doubles start 8-aligned.
  test::RosCameraInfo info{"/i", {1, 2}, 4, 3, {5, 0, 2, 0, 6, 1.5, 0, 0, 1}, {0.1, -0.2, 0, 0, 0.01}};
  const auto decoded = io_detail::ros2_msgs::camera_info(test::cdr_camera_info(info), "le.cdr");
  EXPECT_EQ(decoded.K, info.K);
  EXPECT_EQ(decoded.D, info.D);
  EXPECT_EQ(decoded.distortion_model, "plumb_bob");
  EXPECT_TRUE(test::throws_naming([] { io_detail::ros2_msgs::compressed_image(std::vector<uint8_t>{0, 7, 0, 0}, "x2.cdr"); },
                                  "x2.cdr: CDR encapsulation 0 7 is not plain CDR"));
}

// ------------------------------------------------------------------ bad input (issue 40)

TEST_F(Rosbag2Small, TruncatedFileIsOneError) {
  const std::string mcap = test::read_bytes(write("whole.mcap", "bgr8", "16UC1"));
  test::write_bytes(dir_.path() / "cut.mcap", mcap.substr(0, 12));
  expect_open_error(dir_.path() / "cut.mcap", dir_.path() / "cut.mcap", "truncated MCAP file");
  const std::string db3 = test::read_bytes(write("whole.db3", "bgr8", "16UC1", {Rosbag2Storage::sqlite_jazzy}));
  test::write_bytes(dir_.path() / "cut.db3", db3.substr(0, 2000));
  expect_open_error(dir_.path() / "cut.db3", dir_.path() / "cut.db3", "SQLite");
}

TEST_F(Rosbag2Small, RecordingCutOffReadsEveryCompleteMessage) {
  // No summary, no footer, the last chunk cut: the complete chunks before it are read (warned).
  Rosbag2WriterOptions options;
  options.summary = false;
  options.chunk_bytes = 1;  // one message per chunk
  const std::string mcap = test::read_bytes(write("recording.mcap", "bgr8", "16UC1", options));
  test::write_bytes(dir_.path() / "cut_recording.mcap", mcap.substr(0, mcap.size() * 3 / 4));
  const auto bag = open_dataset(dir_.path() / "cut_recording.mcap");
  EXPECT_EQ(bag->size(), 2u) << "frames 0 and 1 are complete, frame 2's depth is cut";
  EXPECT_TRUE(same_pixels(bag->load(1).rgb, small_.bgr));
  // A bag folder whose metadata.yaml was never written: its storage files in name order.
  Rosbag2WriterOptions split;
  split.messages_per_file = 4;
  const fs::path folder = write("no_metadata", "bgr8", "16UC1", split);
  fs::remove(folder / "metadata.yaml");
  EXPECT_EQ(open_dataset(folder)->size(), 3u);
}

/// The first chunk record of a single-file MCAP written by the test writer: after the magic
/// and the header record.
size_t first_chunk(const std::string& mcap) {
  uint64_t header_length = 0;
  std::memcpy(&header_length, mcap.data() + 9, 8);
  return 8 + 9 + header_length;
}

TEST_F(Rosbag2Small, LengthFieldPastTheEndIsOneError) {
  Rosbag2WriterOptions options;
  options.compression = McapCompression::none;
  options.summary = false;
  std::string mcap = test::read_bytes(write("lengths.mcap", "bgr8", "16UC1", options));
  // The first record inside the first (uncompressed) chunk: its length field made huge.
  const size_t records = first_chunk(mcap) + 9 + 8 + 8 + 8 + 4 + 4 + 8;
  mcap[records + 1 + 6] = 0x7f;
  std::memset(mcap.data() + first_chunk(mcap) + 9 + 24, 0, 4);  // uncompressed_crc 0: not computed (the spec's "none")
  const fs::path bad = dir_.path() / "length_past_end.mcap";
  test::write_bytes(bad, mcap);
  expect_open_error(bad, bad, "runs past the end of the chunk");
  // A CDR sequence length past the end of its message.
  RosImage image = colour_message("/c/image_raw", {1, 0}, small_.bgr, "bgr8");
  std::vector<uint8_t> cdr = test::cdr_image(image);
  const uint32_t huge = 0x7fffffff;
  std::memcpy(cdr.data() + cdr.size() - image.data.size() - 4, &huge, 4);
  const fs::path cdr_bad = dir_.path() / "cdr_length.mcap";
  {
    Rosbag2Writer bag(cdr_bad, {});
    bag.write_raw("/c/image_raw", "sensor_msgs/msg/Image", 1000000000, cdr);
    bag.write(depth_message("/c/depth", {1, 0}, small_.depth_m, "16UC1"));
    bag.write(info_message("/c/camera_info", {1, 0}, small_.k));
  }
  expect_open_error(cdr_bad, cdr_bad, "runs past the end");
}

TEST_F(Rosbag2Small, HugeDeclaredUncompressedSizeIsOneError) {
  Rosbag2WriterOptions options;
  options.summary = false;
  std::string mcap = test::read_bytes(write("huge.mcap", "bgr8", "16UC1", options));
  const uint64_t huge = uint64_t{1} << 40;
  std::memcpy(mcap.data() + first_chunk(mcap) + 9 + 16, &huge, 8);
  const fs::path bad = dir_.path() / "huge_chunk.mcap";
  test::write_bytes(bad, mcap);
  expect_open_error(bad, bad, "declares 1099511627776 uncompressed bytes");
}

TEST_F(Rosbag2Small, UnknownCompressionIsOneError) {
  std::string mcap = test::read_bytes(write("brotli.mcap", "bgr8", "16UC1"));
  const size_t name = first_chunk(mcap) + 9 + 8 + 8 + 8 + 4 + 4;
  ASSERT_EQ(mcap.substr(name, 4), "zstd");
  mcap.replace(name, 4, "brot");
  const fs::path bad = dir_.path() / "unknown_compression.mcap";
  test::write_bytes(bad, mcap);
  expect_open_error(bad, bad, "unknown compression 'brot'");
}

TEST_F(Rosbag2Small, CdrStringWithoutTerminatorIsOneError) {
  std::vector<uint8_t> cdr = test::cdr_image(colour_message("/c/image_raw", {1, 0}, small_.bgr, "bgr8"));
  const std::string encoding("bgr8\0", 5);
  const auto at = std::search(cdr.begin(), cdr.end(), encoding.begin(), encoding.end());
  ASSERT_NE(at, cdr.end());
  at[4] = 'x';
  expect_error([&] { io_detail::ros2_msgs::image(cdr, "x.db3:/c/image_raw"); }, "x.db3:/c/image_raw", "no NUL terminator");
  const fs::path bad = dir_.path() / "unterminated.db3";
  {
    Rosbag2Writer bag(bad, {Rosbag2Storage::sqlite_humble});
    bag.write_raw("/c/image_raw", "sensor_msgs/msg/Image", 1000000000, cdr);
    bag.write(depth_message("/c/depth", {1, 0}, small_.depth_m, "16UC1"));
    bag.write(info_message("/c/camera_info", {1, 0}, small_.k));
  }
  expect_open_error(bad, bad, "no NUL terminator");
}

TEST_F(Rosbag2Small, ImageDataLengthDisagreeingWithHeightTimesStepIsOneError) {
  for (const int extra : {-7, 16}) {
    const fs::path bad = dir_.path() / ("data_length" + std::to_string(extra) + ".mcap");
    {
      Rosbag2Writer bag(bad, {});
      RosImage colour = colour_message("/c/image_raw", {1, 0}, small_.bgr, "bgr8");
      colour.data.resize(colour.data.size() + extra);
      bag.write(colour);
      bag.write(depth_message("/c/depth", {1, 0}, small_.depth_m, "16UC1"));
      bag.write(info_message("/c/camera_info", {1, 0}, small_.k));
    }
    expect_open_error(bad, bad, "height x step is 14400");
  }
}

}  // namespace
}  // namespace semap
