// ScanNet readers (src/io/scannet_dataset.cpp) on an export and a .sens file the test writes
// from ../shared/data/7scenes_redkitchen: colour upscaled to a separate 960x720 camera (as
// ScanNet's 1296x968 colour is), depth in millimetres, camera-to-world poses with one invalid
// (-inf) frame.
#include <libdeflate.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "semap/io/dataset.hpp"
#include "io/image_io.hpp"
#include "io_test_util.hpp"
#include "segmentation/registration.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::throws_naming;

constexpr size_t kFrames = 12;
constexpr size_t kInvalidFrame = 3;  // its pose is written as -inf rows
constexpr double kColourScale = 1.5;  // 640x480 -> 960x720

/// K of the colour camera after upscaling by kColourScale (pixel centres preserved). With the
/// 7-Scenes K (585, 320, 240) every value is exact in float: 877.5, 480.25, 360.25.
PinholeIntrinsics upscaled(const PinholeIntrinsics& k) {
  const double s = kColourScale;
  return {k.fx * s, k.fy * s, (k.cx + 0.5) * s - 0.5, (k.cy + 0.5) * s - 0.5, int(k.width * s), int(k.height * s)};
}

std::string matrix_text(const Eigen::Matrix4d& m) {
  std::string out;
  char buf[64];
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      std::snprintf(buf, sizeof buf, c ? " %.17g" : "%.17g", m(r, c));
      out += buf;
    }
    out += "\n";
  }
  return out;
}

Eigen::Matrix4d k_matrix(const PinholeIntrinsics& k) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = k.fx, m(1, 1) = k.fy, m(0, 2) = k.cx, m(1, 2) = k.cy;
  return m;
}

const std::string kInvalidPose = "-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n";

/// The source frames: 7-Scenes colour upscaled and JPEG-encoded (the bytes both layouts store).
struct Source {
  std::unique_ptr<DatasetReader> sevenscenes;
  std::vector<std::vector<uchar>> jpeg;
  std::vector<fs::path> depth_png;
};

Source load_source(const fs::path& root) {
  Source s;
  s.sevenscenes = open_dataset(root);
  for (size_t i = 0; i < kFrames; ++i) {
    const Frame f = s.sevenscenes->load(i);
    cv::Mat big;
    cv::resize(f.rgb, big, {}, kColourScale, kColourScale, cv::INTER_LINEAR);
    s.jpeg.emplace_back();
    cv::imencode(".jpg", big, s.jpeg.back(), {cv::IMWRITE_JPEG_QUALITY, 95});
    s.depth_png.push_back(f.depth_path);
  }
  return s;
}

void write_export(const Source& s, const fs::path& dir) {
  for (const char* sub : {"color", "depth", "pose", "intrinsic"}) fs::create_directories(dir / sub);
  const PinholeIntrinsics& k = s.sevenscenes->camera().depth;
  test::write_text(dir / "intrinsic" / "intrinsic_depth.txt", matrix_text(k_matrix(k)));
  test::write_text(dir / "intrinsic" / "intrinsic_color.txt", matrix_text(k_matrix(upscaled(k))));
  test::write_text(dir / "intrinsic" / "extrinsic_depth.txt", matrix_text(Eigen::Matrix4d::Identity()));
  test::write_text(dir / "intrinsic" / "extrinsic_color.txt", matrix_text(Eigen::Matrix4d::Identity()));
  for (size_t i = 0; i < kFrames; ++i) {
    const std::string n = std::to_string(i);
    test::write_bytes(dir / "color" / (n + ".jpg"), std::string(s.jpeg[i].begin(), s.jpeg[i].end()));
    fs::copy_file(s.depth_png[i], dir / "depth" / (n + ".png"));
    const auto& pose = s.sevenscenes->records()[i].gt_T_world_camera;
    test::write_text(dir / "pose" / (n + ".txt"), i == kInvalidFrame ? kInvalidPose : matrix_text(pose->matrix()));
  }
}

// ------------------------------------------------------------------ .sens writer (SensorData.h v4)

template <class T>
void put(std::string& out, T v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}
void put_matrix(std::string& out, const Eigen::Matrix4d& m) {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) put(out, static_cast<float>(m(r, c)));
}

std::string zlib(const std::string& raw) {
  libdeflate_compressor* c = libdeflate_alloc_compressor(6);
  std::string out(libdeflate_zlib_compress_bound(c, raw.size()), '\0');
  out.resize(libdeflate_zlib_compress(c, raw.data(), raw.size(), out.data(), out.size()));
  libdeflate_free_compressor(c);
  return out;
}

std::string sens_bytes(const Source& s) {
  const PinholeIntrinsics& k = s.sevenscenes->camera().depth;
  const PinholeIntrinsics kc = upscaled(k);
  std::string out;
  put<uint32_t>(out, 4);
  const std::string name = "StructureSensor";
  put<uint64_t>(out, name.size());
  out += name;
  put_matrix(out, k_matrix(kc));
  put_matrix(out, Eigen::Matrix4d::Identity());
  put_matrix(out, k_matrix(k));
  put_matrix(out, Eigen::Matrix4d::Identity());
  put<int32_t>(out, 2);  // jpeg
  put<int32_t>(out, 1);  // zlib_ushort
  for (uint32_t v : {uint32_t(kc.width), uint32_t(kc.height), uint32_t(k.width), uint32_t(k.height)}) put(out, v);
  put<float>(out, 1000.0f);
  put<uint64_t>(out, kFrames);
  for (size_t i = 0; i < kFrames; ++i) {
    Eigen::Matrix4d pose = s.sevenscenes->records()[i].gt_T_world_camera->matrix();
    if (i == kInvalidFrame) pose.setConstant(-std::numeric_limits<double>::infinity());
    put_matrix(out, pose);
    put<uint64_t>(out, 1000000 + i * 33333);  // colour and depth timestamps, microseconds
    put<uint64_t>(out, 1000000 + i * 33333);
    const cv::Mat raw = cv::imread(s.depth_png[i].string(), cv::IMREAD_UNCHANGED);
    const std::string depth = zlib(std::string(reinterpret_cast<const char*>(raw.data), raw.total() * 2));
    put<uint64_t>(out, s.jpeg[i].size());
    put<uint64_t>(out, depth.size());
    out.append(s.jpeg[i].begin(), s.jpeg[i].end());
    out += depth;
  }
  put<uint64_t>(out, 0);  // IMU frames
  return out;
}

bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

double ms_per_frame(const DatasetReader& reader, size_t frames) {
  double best = 1e9;
  for (int round = 0; round < 3; ++round) {
    const auto t0 = std::chrono::steady_clock::now();
    for (size_t i = 0; i < frames; ++i) reader.load(i);
    best = std::min(best, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / frames);
  }
  return best;
}

class ScanNet : public ::testing::Test {
 protected:
  void SetUp() override {
    SEMAP_REQUIRE_DATA(root, "7scenes_redkitchen");
    source_ = load_source(root);
  }
  /// 7-Scenes frame index of ScanNet frame i (the invalid one is skipped).
  static size_t source_index(size_t i) { return i < kInvalidFrame ? i : i + 1; }

  Source source_;
  test::TempDir dir_{"semap_scannet"};
};

TEST_F(ScanNet, ExportReadsDepthPosesAndASeparateColourCamera) {
  write_export(source_, dir_ / "scene0000_00");
  const auto reader = open_dataset(dir_ / "scene0000_00");
  EXPECT_EQ(reader->format(), "scannet");
  ASSERT_EQ(reader->size(), kFrames - 1);  // the -inf pose is skipped
  const CameraModel& camera = reader->camera();
  EXPECT_EQ(camera.depth, source_.sevenscenes->camera().depth);
  EXPECT_EQ(camera.depth_scale, 1000.0);
  ASSERT_TRUE(camera.colour.has_value());
  EXPECT_EQ(camera.colour->intrinsics, upscaled(camera.depth));
  EXPECT_TRUE(camera.colour->T_depth_colour.matrix().isIdentity(0));

  size_t same_depth = 0, same_pose = 0, same_time = 0;
  double registered_diff = 0, shifted_diff = 0;
  CameraModel shifted = camera;  // control: colour principal point off by one depth pixel
  shifted.colour->intrinsics.cx += kColourScale;
  const auto mean_diff = [](const Frame& f, const CameraModel& cam, const cv::Mat& reference) {
    const cv::Mat registered = register_image(f.rgb, colour_lookup_map(f.depth, cam), cv::INTER_LINEAR);
    cv::Mat diff;
    cv::absdiff(registered, reference, diff);
    return cv::mean(diff, f.depth > 0)[0];
  };
  for (size_t i = 0; i < reader->size(); ++i) {
    const Frame f = reader->load(i);
    const Frame ref = source_.sevenscenes->load(source_index(i));
    same_depth += same_pixels(f.depth, ref.depth);
    same_pose += f.gt_T_world_camera && f.gt_T_world_camera->isApprox(*ref.gt_T_world_camera, 1e-12);
    same_time += std::abs(f.timestamp - source_index(i) / 30.0) < 1e-12;
    ASSERT_EQ(f.rgb.size(), cv::Size(960, 720));
    // METHODS.md B2: colour registered to depth must land back on the 640x480 colour.
    registered_diff += mean_diff(f, camera, ref.rgb) / reader->size();
    shifted_diff += mean_diff(f, shifted, ref.rgb) / reader->size();
  }
  EXPECT_EQ(same_depth, reader->size());
  EXPECT_EQ(same_pose, reader->size());
  EXPECT_EQ(same_time, reader->size());
  std::cout << "[scannet] registered colour vs original: mean |diff| " << registered_diff
            << " grey levels (one pixel off: " << shifted_diff << ")" << std::endl;
  EXPECT_LT(registered_diff, 3.0);  // JPEG + resampling only
  EXPECT_GT(shifted_diff, 1.5 * registered_diff);
}

TEST_F(ScanNet, SensFileReadsLikeTheExport) {
  write_export(source_, dir_ / "export");
  test::write_bytes(dir_ / "scene.sens", sens_bytes(source_));
  const auto exported = open_dataset(dir_ / "export");
  const auto sens = open_dataset(dir_ / "scene.sens");
  EXPECT_EQ(sens->format(), "scannet-sens");
  ASSERT_EQ(sens->size(), kFrames - 1);
  EXPECT_EQ(sens->camera().depth, exported->camera().depth);
  ASSERT_TRUE(sens->camera().colour.has_value());
  EXPECT_EQ(sens->camera().colour->intrinsics, exported->camera().colour->intrinsics);
  size_t same = 0;
  for (size_t i = 0; i < sens->size(); ++i) {
    const Frame a = sens->load(i), b = exported->load(i);
    same += same_pixels(a.rgb, b.rgb) && same_pixels(a.depth, b.depth) &&
            a.gt_T_world_camera->isApprox(*b.gt_T_world_camera, 1e-6) &&
            std::abs(a.timestamp - (1.0 + source_index(i) * 0.033333)) < 1e-9;
  }
  EXPECT_EQ(same, sens->size());

  // Reading overhead per frame against the TUM folder in the same run.
  SEMAP_REQUIRE_DATA(tum, "tum_fr1_rpy");
  const auto tum_reader = open_dataset(tum);
  const double tum_ms = ms_per_frame(*tum_reader, sens->size()), export_ms = ms_per_frame(*exported, sens->size()),
               sens_ms = ms_per_frame(*sens, sens->size());
  std::cout << "[scannet] load: export " << export_ms << " ms/frame, .sens " << sens_ms
            << " ms/frame (960x720 JPEG colour); TUM folder " << tum_ms << " ms/frame" << std::endl;

  // A cut file: one line naming it.
  const std::string bytes = test::read_bytes(dir_ / "scene.sens");
  test::write_bytes(dir_ / "cut.sens", bytes.substr(0, bytes.size() / 2));
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir_ / "cut.sens"); }, "cut.sens: truncated .sens file"));
  test::write_bytes(dir_ / "text.sens", "not a sens file at all");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir_ / "text.sens"); }, "text.sens: not a ScanNet .sens file"));
}

TEST_F(ScanNet, BadExportsNameTheFile) {
  const fs::path dir = dir_ / "bad";
  write_export(source_, dir);
  // Intrinsics of the original colour size with resized images: the principal point is outside.
  test::write_text(dir / "intrinsic" / "intrinsic_color.txt", "1170 0 1000 0\n0 1170 800 0\n0 0 1 0\n0 0 0 1\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "intrinsic_color.txt: principal point"));
  fs::remove(dir / "intrinsic" / "intrinsic_color.txt");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "intrinsic_color.txt: not found, and the colour images differ"));
  test::write_text(dir / "intrinsic" / "intrinsic_color.txt", "1 2 3\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "intrinsic_color.txt: expected a 4x4"));
  fs::remove(dir / "depth" / "5.png");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "5.png: depth image for 5.jpg not found"));
  for (size_t i = 0; i < kFrames; ++i) test::write_text(dir / "pose" / (std::to_string(i) + ".txt"), kInvalidPose);
  fs::copy_file(source_.depth_png[5], dir / "depth" / "5.png");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "every pose is invalid"));
}

}  // namespace
}  // namespace semap
