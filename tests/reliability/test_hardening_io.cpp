// Issue 22 at the library level, by the issue's headings: "Crashes, hangs, memory" (camera
// magnitudes, image bombs in every format, FIFOs / devices / folders as inputs, georeferenced
// ground truth) and "Silent wrong results and unclear errors" (config strictness, messages that
// name the file and say what it is, evaluation edge cases). Every input is generated here.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "semap/core/camera.hpp"
#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "semap/eval/object_metrics.hpp"
#include "semap/eval/semantic_metrics.hpp"
#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/config_loader.hpp"
#include "semap/io/dataset.hpp"
#include "io/image_header.hpp"
#include "io/image_io.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"
#include "reliability/reliability_support.hpp"
#include "synth/synth_config.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::data_lines;
using test::join_lines;
using test::listed;
using test::slurp;
using test::spit;

/// The message of the semap::Error `fn` throws ("" when it throws nothing or something else).
template <class F>
std::string error_of(F&& fn) {
  try {
    fn();
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("NOT A semap::Error: ") + e.what();
  }
  return "";
}

::testing::AssertionResult mentions(const std::string& message, const std::string& part) {
  if (message.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << message << "' does not mention '" << part << "'";
}

/// No run of 20 digits: numbers are printed compactly (never DBL_MAX's 309 digits).
bool compact(const std::string& message) { return !std::regex_search(message, std::regex("[0-9]{20}")); }

long max_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024;
}

/// A small synthetic dataset (6 frames, 160x120), made once per test binary.
const fs::path& small_dataset() {
  static test::TempDir dir("semap_hardening_io");
  static const fs::path path = [] {
    SynthConfig cfg;
    cfg.frames = 6;
    cfg.objects = 3;
    cfg.width = 160;
    cfg.height = 120;
    cfg.gt_point_spacing = 0.05;
    generate_dataset(cfg, dir / "clean");
    return dir / "clean";
  }();
  return path;
}

fs::path copy_of(const test::TempDir& tmp, const std::string& name) {
  const fs::path dir = tmp / name;
  fs::copy(small_dataset(), dir, fs::copy_options::recursive);
  return dir;
}

// ------------------------------------------------------------ Crashes, hangs, memory

TEST(HardeningCamera, PresetsPassAndUnphysicalMagnitudesAreRefusedNamingTheKey) {
  for (int fr : {1, 2, 3}) EXPECT_NO_THROW(validate_camera(tum_camera_preset(fr), "tum"));
  CameraModel base = tum_camera_preset(1);
  const auto with = [&](auto change) {
    CameraModel c = base;
    change(c);
    return error_of([&] { validate_camera(c, "dataset.yaml"); });
  };
  const std::vector<std::pair<std::string, std::string>> cases = {
      {with([](CameraModel& c) { c.depth.cx = 1e12; }), "cx = 1e+12"},
      {with([](CameraModel& c) { c.depth.cx = 1e6; }), "cx = 1e+06"},
      {with([](CameraModel& c) { c.depth.cy = -3; }), "cy = -3"},
      {with([](CameraModel& c) { c.depth.fx = 1e-9; }), "fx = 1e-09"},
      {with([](CameraModel& c) { c.depth.fy = 1e9; }), "fy = 1e+09"},
      {with([](CameraModel& c) { c.depth.fx = std::nan(""); }), "fx = nan"},
      {with([](CameraModel& c) { c.depth.width = 100000; }), "width = 100000"},
      {with([](CameraModel& c) { c.depth.height = 0; }), "height = 0"},
      {with([](CameraModel& c) { c.depth.width = c.depth.height = 16384; c.depth.cx = c.depth.cy = 8192; c.depth.fx = c.depth.fy = 9000; }), "width x height"},
      {with([](CameraModel& c) { c.depth_scale = 1e-9; }), "depth_scale = 1e-09"},
      {with([](CameraModel& c) { c.depth_scale = 1.79769e308; }), "depth_scale = 1.79769e+308"},
      {with([](CameraModel& c) { c.colour = CameraModel::ColourCamera{c.depth, Pose::Identity()}; c.colour->intrinsics.cx = 1e12; }), "colour.cx"},
      {with([](CameraModel& c) {
         c.colour = CameraModel::ColourCamera{c.depth, Pose::Identity()};
         c.colour->T_depth_colour.translation() = Eigen::Vector3d(5, 0, 0);
       }), "baseline"},
      // Issue 44 (third round), class 3 variant: a colour extrinsic that scales or shears (a
      // saved map's camera section was accepted with it and registered colours wrongly).
      {with([](CameraModel& c) {
         c.colour = CameraModel::ColourCamera{c.depth, Pose::Identity()};
         c.colour->T_depth_colour.linear() *= 2.0;
       }), "colour.T_depth_colour is not a rigid transform"},
      {with([](CameraModel& c) {
         c.colour = CameraModel::ColourCamera{c.depth, Pose::Identity()};
         c.colour->T_depth_colour.linear()(0, 1) = 0.3;
       }), "colour.T_depth_colour is not a rigid transform"},
  };
  for (const auto& [message, part] : cases) {
    EXPECT_TRUE(mentions(message, "dataset.yaml: camera")) << message;
    EXPECT_TRUE(mentions(message, part));
    EXPECT_TRUE(compact(message)) << message;
  }
}

TEST(HardeningCamera, OpenDatasetRefusesTheCameraNamingItsFile) {
  test::TempDir tmp("semap_hardening_cam");
  const fs::path dir = copy_of(tmp, "cx");
  const std::string yaml = slurp(dir / "dataset.yaml");
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"cx: ", "cx: 1e12 #"}, {"fx: ", "fx: 1e-9 #"}, {"depth_scale: 5000", "depth_scale: 1e-12"}}) {
    std::string changed = yaml;
    changed.replace(changed.find(from), from.size(), to);
    // The flow map keeps going after the comment on the next line: rewrite as block style.
    changed = std::regex_replace(changed, std::regex(" #[^,}]*"), "");
    spit(dir / "dataset.yaml", changed);
    const std::string message = error_of([&] { open_dataset(dir); });
    EXPECT_TRUE(mentions(message, "dataset.yaml")) << changed;
    EXPECT_TRUE(mentions(message, to.substr(0, to.find(':'))));
  }
  // 7-Scenes: the intrinsic matrix file is named.
  const fs::path scenes = tmp / "scenes";
  fs::create_directories(scenes);
  write_image(scenes / "frame-000000.color.png", cv::Mat(480, 640, CV_8UC3, cv::Scalar(1, 2, 3)));
  write_depth_image(scenes / "frame-000000.depth.png", cv::Mat(480, 640, CV_32FC1, cv::Scalar(1.0f)), 1000.0);
  spit(scenes / "camera-intrinsics.txt", "585 0 1e12\n0 585 240\n0 0 1\n");
  EXPECT_TRUE(mentions(error_of([&] { open_dataset(scenes); }), "camera-intrinsics.txt: camera cx = 1e+12"));
}

/// Bytes of an image of `ext` made by OpenCV (empty when this OpenCV cannot write it).
std::string encoded(const std::string& ext, const cv::Mat& image) {
  std::vector<uchar> buffer;
  try {
    if (!cv::imencode(ext, image, buffer)) return {};
  } catch (const cv::Exception&) {
    return {};
  }
  return std::string(buffer.begin(), buffer.end());
}

void put_be16(std::string& b, size_t pos, uint32_t v) {
  b[pos] = char(v >> 8);
  b[pos + 1] = char(v & 0xff);
}
void put_le32(std::string& b, size_t pos, uint32_t v) {
  for (int k = 0; k < 4; ++k) b[pos + k] = char((v >> (8 * k)) & 0xff);
}

/// Each format's header rewritten to declare 16384x16384 pixels (the JPEG of the issue is 349
/// bytes; the BMP is run-length coded: a few bytes could fill the whole size).
std::vector<std::pair<std::string, std::string>> image_bombs() {
  const cv::Mat small(24, 32, CV_8UC3, cv::Scalar(40, 80, 120));
  std::vector<std::pair<std::string, std::string>> bombs;
  std::string png = encoded(".png", small);
  put_le32(png, 16, 0), put_be16(png, 18, 16384), put_le32(png, 20, 0), put_be16(png, 22, 16384);
  bombs.emplace_back("bomb.png", png);
  std::string jpg = encoded(".jpg", small);
  for (size_t pos = 2; pos + 9 < jpg.size();) {
    const auto marker = static_cast<unsigned char>(jpg[pos + 1]);
    if (marker == 0xC0 || marker == 0xC2) {
      put_be16(jpg, pos + 5, 16384), put_be16(jpg, pos + 7, 16384);
      break;
    }
    pos += 2 + ((static_cast<unsigned char>(jpg[pos + 2]) << 8) | static_cast<unsigned char>(jpg[pos + 3]));
  }
  bombs.emplace_back("bomb.jpg", jpg);
  std::string bmp(54, '\0');  // BITMAPINFOHEADER, 8-bit, BI_RLE8, then a few run codes
  bmp[0] = 'B', bmp[1] = 'M';
  put_le32(bmp, 10, 54 + 1024), put_le32(bmp, 14, 40), put_le32(bmp, 18, 16384), put_le32(bmp, 22, 16384);
  bmp[26] = 1, bmp[28] = 8, bmp[30] = 1;
  bmp += std::string(1024, '\0') + std::string("\xff\x01\xff\x01\x00\x01", 6);
  bombs.emplace_back("bomb_rle.bmp", bmp);
  std::string tiff("II*\0\x08\0\0\0", 8);  // one directory: width, length, samples
  tiff += std::string("\x03\0", 2);
  for (const auto& [tag, type, value] : {std::tuple{256, 4, 16384}, std::tuple{257, 4, 16384}, std::tuple{277, 3, 3}}) {
    std::string e(12, '\0');
    e[0] = char(tag & 0xff), e[1] = char(tag >> 8), e[2] = char(type), e[4] = 1;
    put_le32(e, 8, static_cast<uint32_t>(value));
    tiff += e;
  }
  tiff += std::string(4, '\0') + std::string(64, '\x11');
  bombs.emplace_back("bomb.tiff", tiff);
  bombs.emplace_back("bomb.ppm", "P6\n# comment\n16384 16384\n255\n" + std::string(64, '\x22'));
  std::string webp = "RIFF" + std::string(4, '\0') + "WEBPVP8X" + std::string("\x0a\0\0\0", 4) + std::string(4, '\0');
  webp += std::string("\xff\x3f\x00\xff\x3f\x00", 6) + std::string(32, '\0');
  bombs.emplace_back("bomb.webp", webp);
  return bombs;
}

TEST(HardeningImages, EveryFormatsDeclaredSizeIsCheckedBeforeDecoding) {
  test::TempDir tmp("semap_hardening_img");
  // Real files of every accepted format: their header size is read exactly.
  const cv::Mat image(23, 37, CV_8UC3, cv::Scalar(10, 20, 30));
  size_t formats = 0;
  for (const char* ext : {".png", ".jpg", ".bmp", ".tiff", ".ppm", ".webp"}) {
    const std::string bytes = encoded(ext, image);
    if (bytes.empty()) continue;
    ++formats;
    const auto header = io_detail::read_image_header(bytes, ext);
    EXPECT_EQ(header.width, 37u) << ext;
    EXPECT_EQ(header.height, 23u) << ext;
    spit(tmp / (std::string("ok") + ext), bytes);
    EXPECT_EQ(read_colour_image(tmp / (std::string("ok") + ext)).size(), cv::Size(37, 23)) << ext;
  }
  EXPECT_GE(formats, 5u);
  // PNM numbers end at any byte, as in OpenCV's reader: "2#1" is width 2, height 1 (fuzz_image
  // found a file whose header was read as 2x5 while OpenCV decoded 2x1).
  const std::string pnm = std::string("P5\f#comment\n\f2#1\n5 75 7");
  const auto pnm_header = io_detail::read_image_header(pnm, "odd.pgm");
  EXPECT_EQ(pnm_header.width, 2u);
  EXPECT_EQ(pnm_header.height, 1u);
  // A comment ends at '\r' too, as in OpenCV's reader (fuzz_image: "#..\r5" is width 5).
  const std::string cr_comment = std::string("P5\n#x\r5 3\n255\n") + std::string(15, '\x7f');
  const auto cr_header = io_detail::read_image_header(cr_comment, "cr.pgm");
  EXPECT_EQ(cr_header.width, 5u);
  EXPECT_EQ(cr_header.height, 3u);
  spit(tmp / "cr.pgm", cr_comment);
  EXPECT_EQ(read_label_image(tmp / "cr.pgm").size(), cv::Size(5, 3));

  const long rss_before = max_rss_mb();
  for (const auto& bomb : image_bombs()) {
    const std::string& name = bomb.first;  // named: clang 14 cannot capture structured bindings
    const std::string& bytes = bomb.second;
    spit(tmp / name, bytes);
    const auto t0 = std::chrono::steady_clock::now();
    const std::string message = error_of([&] { read_colour_image(tmp / name); });
    EXPECT_TRUE(mentions(message, name));
    EXPECT_TRUE(mentions(message, "16384x16384")) << name;
    EXPECT_TRUE(mentions(error_of([&] { read_label_image(tmp / name); }), "16384x16384"));
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0) << name;
  }
  // A decode of any of them would take 805 MB (16384^2 x 3 bytes).
  EXPECT_LT(max_rss_mb() - rss_before, 150) << "MB of memory grew while refusing the bombs";

  // Formats nobody checked are not handed to a decoder.
  for (const auto& format : std::vector<std::pair<std::string, std::string>>{
           {"x.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16384 +X 16384\n"},
           {"x.exr", std::string("\x76\x2f\x31\x01", 4) + std::string(60, '\0')},
           {"x.ras", std::string("\x59\xa6\x6a\x95", 4) + std::string(60, '\0')},
           {"x.pfm", "PF\n16384 16384\n-1\n"}}) {
    const std::string& name = format.first;
    const std::string& bytes = format.second;
    spit(tmp / name, bytes);
    EXPECT_TRUE(mentions(error_of([&] { read_colour_image(tmp / name); }), "unsupported image format")) << name;
  }
}

TEST(HardeningFiles, FifosDevicesFoldersAndLinksAreRefusedSayingWhatTheyAre) {
  test::TempDir tmp("semap_hardening_files");
  const fs::path fifo = tmp / "pipe.txt", folder = tmp / "folder.yaml";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  fs::create_directories(folder);
  fs::create_symlink(tmp / "nowhere.txt", tmp / "dangling.txt");
  fs::create_symlink(tmp / "loop_b", tmp / "loop_a");
  fs::create_symlink(tmp / "loop_a", tmp / "loop_b");
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<std::pair<fs::path, std::string>> kinds = {{fifo, "is a FIFO (named pipe)"},
                                                               {"/dev/zero", "is a character device"},
                                                               {folder, "is a folder"},
                                                               {tmp / "dangling.txt", "is a dangling symlink"},
                                                               {tmp / "loop_a", "is a symlink loop"},
                                                               {tmp / "absent.txt", "not found"},
                                                               {tmp / std::string(300, 'n'), "name too long"}};
  for (const auto& entry : kinds) {
    const fs::path& path = entry.first;
    const std::string& kind = entry.second;
    SCOPED_TRACE(path.string().substr(0, 80));
    // Every reader goes through the one helper: lists/trajectories, configs, images, meshes, JSON.
    EXPECT_TRUE(mentions(error_of([&] { read_tum_trajectory(path); }), kind));
    EXPECT_TRUE(mentions(error_of([&] { load_config_file(path, [](ParamVisitor&) {}); }), kind));
    EXPECT_TRUE(mentions(error_of([&] { read_colour_image(path); }), kind));
    EXPECT_TRUE(mentions(error_of([&] { read_ply(path); }), kind));
    EXPECT_TRUE(mentions(error_of([&] { load_map_objects(path); }), kind));
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0) << "nothing blocks";
  // Size limits.
  spit(tmp / "big.txt", std::string(5000, 'x'));
  EXPECT_TRUE(mentions(error_of([&] { read_regular_file(tmp / "big.txt", 4096, "list file"); }), "more than the limit"));
  EXPECT_EQ(read_regular_file(tmp / "big.txt", 5000).size(), 5000u);
}

TEST(HardeningGroundTruth, GeoreferencedPosesGetALocalOriginOthersAreUntouched) {
  test::TempDir tmp("semap_hardening_gt");
  const fs::path geo = copy_of(tmp, "geo");
  test::georeference(geo / "groundtruth.txt", {512345.25, 5412345.5, 312.75});
  const auto clean = open_dataset(small_dataset()), local = open_dataset(geo);
  const Trajectory a = clean->ground_truth(), b = local->ground_truth();
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GE(a.size(), 6u);
  EXPECT_LT(b.front().T_world_camera.translation().norm(), 1e-9) << "the first pose is the local origin";
  for (size_t i = 0; i < a.size(); ++i) {
    const Eigen::Vector3d expected = a[i].T_world_camera.translation() - a.front().T_world_camera.translation();
    EXPECT_LT((b[i].T_world_camera.translation() - expected).norm(), 1e-6) << i;
    EXPECT_LT((b[i].T_world_camera.linear() - a[i].T_world_camera.linear()).norm(), 1e-9) << i;
  }
  // Ground truth near the origin keeps its frame.
  EXPECT_GT(a.front().T_world_camera.translation().norm(), 0.5);
}

// ------------------------------------------------------------ Silent wrong results and unclear errors

struct SmallConfig {
  double voxel_size = 0.02;
  int n = 3;
  void visit(ParamVisitor& v) {
    v.section("tsdf", "", [&](ParamVisitor& s) {
      s.param("voxel_size", voxel_size, "m", "");
      s.param("n", n, "", "");
    });
  }
};

std::string load_error(const std::string& yaml) {
  SmallConfig c;
  return error_of([&] { load_config_string(yaml, "c.yaml", [&](ParamVisitor& v) { c.visit(v); }); });
}

TEST(HardeningConfig, DuplicateKeysExtraDocumentsAndBomsAreHandled) {
  EXPECT_TRUE(mentions(load_error("tsdf:\n  voxel_size: 0.02\n  voxel_size: 0.05\n"),
                       "c.yaml:3: duplicate key 'voxel_size' (first at line 2)"));
  EXPECT_TRUE(mentions(load_error("tsdf: {n: 1}\ntsdf: {n: 2}\n"), "duplicate key 'tsdf'"));
  EXPECT_TRUE(mentions(load_error("tsdf: {n: 1, n: 1}\n"), "duplicate key 'n'"));
  EXPECT_TRUE(mentions(load_error("tsdf: {n: 1}\n---\ntsdf: {n: 2}\n"), "second YAML document"));
  EXPECT_TRUE(mentions(load_error("tsdf: {n: 1}\n...\n---\n"), "second YAML document"));
  // yaml-cpp's LoadAll never ends on a lone ',' (fuzz_dataset_yaml): one line, at once.
  for (const char* stuck : {",", "tsdf: {n: 1}\n,\n"}) EXPECT_TRUE(mentions(load_error(stuck), "malformed YAML")) << stuck;
  // A UTF-8 byte-order mark (Windows editors) is skipped, the values apply.
  SmallConfig c;
  load_config_string("\xEF\xBB\xBFtsdf:\n  voxel_size: 0.05\n", "bom.yaml", [&](ParamVisitor& v) { c.visit(v); });
  EXPECT_DOUBLE_EQ(c.voxel_size, 0.05);
  // An invisible no-break space in a value is shown in the message.
  EXPECT_TRUE(mentions(load_error("tsdf:\n  n: \xC2\xA0" "3\n"), "\\u{00A0}"));
  // The dataset.yaml goes through the same strict parse.
  test::TempDir tmp("semap_hardening_cfg");
  const fs::path dir = copy_of(tmp, "dup");
  spit(dir / "dataset.yaml", slurp(dir / "dataset.yaml") + "format: tum\n");
  EXPECT_TRUE(mentions(error_of([&] { open_dataset(dir); }), "duplicate key 'format'"));
}

TEST(HardeningMessages, ListedFilesSayWhatIsWrongAndHugeNamesAreShortened) {
  test::TempDir tmp("semap_hardening_msg");
  const auto frame = [&](const fs::path& d, size_t k) { return listed(d / "rgb.txt", k); };
  {
    const fs::path d = copy_of(tmp, "folder");
    fs::remove(frame(d, 1));
    fs::create_directories(frame(d, 1));
    EXPECT_TRUE(mentions(error_of([&] { open_dataset(d); }), "is a folder, expected a regular file"));
  }
  {
    const fs::path d = copy_of(tmp, "dangling");
    fs::remove(frame(d, 2));
    fs::create_symlink(d / "gone.png", frame(d, 2));
    EXPECT_TRUE(mentions(error_of([&] { open_dataset(d); }), "is a dangling symlink"));
  }
  {
    const fs::path d = copy_of(tmp, "loop");
    fs::remove(frame(d, 3));
    fs::create_symlink(frame(d, 3), frame(d, 3));
    EXPECT_TRUE(mentions(error_of([&] { open_dataset(d); }), "is a symlink loop"));
  }
  {
    const fs::path d = copy_of(tmp, "spaces");
    auto lines = data_lines(d / "rgb.txt");
    const std::string stamp = lines[1].substr(0, lines[1].find(' '));
    fs::rename(frame(d, 1), d / "rgb" / "my frame.png");
    lines[1] = stamp + " rgb/my frame.png";
    spit(d / "rgb.txt", join_lines(lines));
    EXPECT_TRUE(mentions(error_of([&] { open_dataset(d); }), "'rgb/my frame.png' exists; rename it without spaces"));
  }
  {
    // A BOM before the first line and names outside the folder (absolute, "../") are read
    // (README: allowed, with one warning per list).
    const fs::path d = copy_of(tmp, "outside");
    auto lines = data_lines(d / "rgb.txt");
    fs::copy_file(frame(d, 0), tmp / "outside0.png");
    lines[0] = lines[0].substr(0, lines[0].find(' ')) + " ../outside0.png";
    lines[1] = lines[1].substr(0, lines[1].find(' ')) + " " + fs::absolute(frame(d, 1)).string();
    spit(d / "rgb.txt", "\xEF\xBB\xBF# with a BOM\n" + join_lines(lines));
    const auto reader = open_dataset(d);
    EXPECT_EQ(reader->size(), 6u);
    EXPECT_EQ(reader->load(0).rgb.size(), cv::Size(160, 120));
  }
  // A 10 MB name is shortened in the message; control characters cannot break the line.
  const std::string huge(10'000'000, 'a');
  const std::string message = Error(huge + "\n.txt", "not found").what();
  EXPECT_LT(message.size(), 3000u);
  EXPECT_TRUE(mentions(message, "characters"));
  EXPECT_EQ(message.find('\n'), std::string::npos);
  EXPECT_TRUE(mentions(error_of([&] { io_detail::read_image_header("\xC2\xA0junk", "x.png"); }), "unsupported"));
}

TEST(HardeningEval, DuplicateIdsRpeWithoutPairsAndNonFiniteVertices) {
  test::TempDir tmp("semap_hardening_eval");
  spit(tmp / "objects.json", R"({"objects": [{"id": 4, "class": "cup", "point_count": 0},
                                             {"id": 5, "class": "cup", "point_count": 0},
                                             {"id": 4, "class": "chair", "point_count": 0}]})");
  EXPECT_TRUE(mentions(error_of([&] { load_map_objects(tmp / "objects.json"); }), "\"id\" 4 appears twice (objects 0 and 2)"));
  nlohmann::json scene = nlohmann::json::parse(slurp(small_dataset() / "scene.json"));
  scene["objects"].push_back(scene["objects"][0]);
  spit(tmp / "scene.json", scene.dump());
  EXPECT_TRUE(mentions(error_of([&] { load_gt_objects(tmp / "scene.json", 0.01); }), "appears twice"));

  // RPE over a sequence shorter than the delta: undefined (null and why), never 0 (perfect).
  Trajectory gt;
  for (int i = 0; i < 5; ++i) gt.push_back({0.1 * i, Pose(Eigen::Translation3d(0.01 * i, 0, 0))});
  const RpeResult rpe = compute_rpe(gt, gt, 1.0);
  EXPECT_EQ(rpe.pairs, 0u);
  const nlohmann::json j = to_json(rpe);
  EXPECT_TRUE(j["trans_rmse_m_per_s"].is_null());
  EXPECT_TRUE(j["rot_rmse_deg_per_s"].is_null());
  EXPECT_TRUE(mentions(j["reason"].get<std::string>(), "1 s apart"));

  // NaN/Inf vertices are excluded and counted: the surface error stays that of the rest.
  PointCloud cloud;
  for (int i = 0; i < 400; ++i) {
    cloud.points.emplace_back(0.01f * (i % 20), 0.01f * (i / 20), 1.0f);
    cloud.labels.push_back(id(Label::kTable));
  }
  PointCloud map = cloud;
  const float bad[3] = {std::nanf(""), INFINITY, -INFINITY};
  for (int k = 0; k < 9; ++k) {
    map.points.emplace_back(0.1f, bad[k % 3], 1.0f);
    map.labels.push_back(id(Label::kTable));
  }
  const SemanticEvaluation e = evaluate_semantic(cloud, map);
  EXPECT_EQ(e.map_vertices_non_finite, 9u);
  EXPECT_TRUE(std::isfinite(e.surface_error_mean_m));
  EXPECT_LT(e.surface_error_mean_m, 1e-6);
  EXPECT_NEAR(e.miou, 1.0, 1e-9);
  EXPECT_EQ(to_json(e)["map_vertices_non_finite"].get<size_t>(), 9u);
}

}  // namespace
}  // namespace semap
