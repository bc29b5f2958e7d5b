// ScanNet: the exported layout (SensReader's export: color/N.jpg, depth/N.png in millimetres,
// pose/N.txt 4x4 camera-to-world, intrinsic/intrinsic_{color,depth}.txt and
// extrinsic_{color,depth}.txt 4x4) and the .sens recording it is exported from. Colour
// (1296x968) and depth (640x480) are separate cameras: the colour camera goes into
// CameraModel::colour and the stages register colour to depth (METHODS.md B2). Frames whose
// pose is invalid (ScanNet writes -inf rows where its reconstruction lost track) are skipped
// and counted.
#include <libdeflate.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"
#include "io/dataset_layouts.hpp"
#include "io/image_io.hpp"
#include "io/text_util.hpp"

namespace semap::io_detail {

namespace fs = std::filesystem;

namespace {

constexpr double kScanNetFrameRate = 30.0;  // the export has no timestamps
constexpr double kScanNetDepthScale = 1000.0;

/// fx, fy, cx, cy of a 4x4 (or 3x3) intrinsic matrix file.
PinholeIntrinsics read_intrinsic_matrix(const fs::path& file) {
  const std::vector<double> m = read_numbers(file);
  if (m.size() != 16 && m.size() != 9) throw Error(file, "expected a 4x4 (or 3x3) intrinsic matrix");
  for (double v : m)
    if (!std::isfinite(v)) throw Error(file, "NaN or Inf in the intrinsic matrix");
  const size_t row = m.size() == 16 ? 4 : 3;
  PinholeIntrinsics k;
  k.fx = m[0], k.cx = m[2], k.fy = m[row + 1], k.cy = m[row + 2];
  if (!(k.fx > 0 && k.fy > 0)) throw Error(file, "intrinsic matrix has no positive focal lengths");
  return k;
}

/// METHODS.md B2: with extrinsics E (common frame -> camera), T_depth_colour = E_depth * E_colour^-1.
Pose depth_from_colour(const Pose& E_colour, const Pose& E_depth) { return E_depth * E_colour.inverse(); }

Pose read_extrinsic(const fs::path& file) {
  if (!fs::exists(file)) return Pose::Identity();
  const auto pose = read_matrix_pose(file);
  if (!pose) throw Error(file, "NaN or Inf in the extrinsic matrix");
  return *pose;
}

/// Intrinsics of a camera whose images are `size`; errors when the principal point is
/// outside them (e.g. an export resized without rescaling its intrinsics).
PinholeIntrinsics with_size(PinholeIntrinsics k, cv::Size size, const fs::path& intrinsic_file, const fs::path& image) {
  k.width = size.width, k.height = size.height;
  if (!(k.cx > 0 && k.cx < k.width && k.cy > 0 && k.cy < k.height))
    throw Error(intrinsic_file, "principal point (" + std::to_string(k.cx) + ", " + std::to_string(k.cy) +
                                    ") lies outside the " + std::to_string(k.width) + "x" + std::to_string(k.height) +
                                    " images (" + image.filename().string() + "); resized export?");
  return k;
}

/// Drops frames whose pose is known to be invalid; says how many.
void skip_invalid_poses(std::vector<FrameRecord>& records, const std::vector<bool>& invalid, const fs::path& source) {
  std::vector<FrameRecord> kept;
  for (size_t i = 0; i < records.size(); ++i)
    if (!invalid[i]) kept.push_back(std::move(records[i]));
  const size_t skipped = records.size() - kept.size();
  if (skipped > 0)
    spdlog::warn("{}: skipped {} of {} frames with an invalid pose (-inf)", source.string(), skipped, records.size());
  records = std::move(kept);
}

/// color/N.{jpg,png} in numeric order (N = frame number).
std::vector<std::pair<long, fs::path>> numbered_colour_images(const fs::path& dir) {
  std::vector<std::pair<long, fs::path>> out;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string stem = it->path().stem().string(), ext = it->path().extension().string();
    if (ext != ".jpg" && ext != ".png") continue;
    if (stem.empty() || !std::all_of(stem.begin(), stem.end(), [](unsigned char c) { return std::isdigit(c); })) continue;
    long number = 0;  // not std::stol: its out_of_range said only "stol" (issue 44, class 8)
    if (std::from_chars(stem.data(), stem.data() + stem.size(), number).ec != std::errc())
      throw Error(it->path(), "frame number " + stem + " is out of range");
    out.emplace_back(number, it->path());
  }
  if (ec) throw Error(dir, "cannot list folder: " + ec.message());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

std::unique_ptr<DatasetReader> open_scannet(const fs::path& root, const DatasetYaml* yaml) {
  const fs::path intrinsic = root / "intrinsic";
  std::vector<FrameRecord> records;
  std::vector<bool> invalid;
  const bool has_poses = fs::is_directory(root / "pose");
  for (const auto& [n, colour] : numbered_colour_images(root / "color")) {
    FrameRecord r;
    r.timestamp = n / kScanNetFrameRate;
    r.rgb = colour;
    r.depth = root / "depth" / (std::to_string(n) + ".png");
    if (!fs::is_regular_file(r.depth)) throw Error(r.depth, "depth image for " + colour.filename().string() + " not found");
    bool bad = false;
    if (has_poses) {
      const fs::path pose_file = root / "pose" / (std::to_string(n) + ".txt");
      if (!fs::is_regular_file(pose_file)) throw Error(pose_file, "pose for " + colour.filename().string() + " not found");
      r.gt_T_world_camera = read_matrix_pose(pose_file);
      bad = !r.gt_T_world_camera;
    }
    records.push_back(std::move(r));
    invalid.push_back(bad);
  }
  if (records.empty()) throw Error(root / "color", "no colour images (N.jpg)");
  skip_invalid_poses(records, invalid, root);
  if (records.empty()) throw Error(root / "pose", "every pose is invalid (-inf)");

  // Image sizes from the first frame (the export does not store them).
  CameraModel camera;
  camera.depth_scale = kScanNetDepthScale;
  const cv::Size depth_size = read_depth_image(records[0].depth, camera.depth_scale).size();
  const cv::Size colour_size = read_colour_image(records[0].rgb).size();
  camera.depth = with_size(read_intrinsic_matrix(intrinsic / "intrinsic_depth.txt"), depth_size,
                           intrinsic / "intrinsic_depth.txt", records[0].depth);
  const fs::path colour_file = intrinsic / "intrinsic_color.txt";
  CameraModel::ColourCamera colour;
  if (fs::exists(colour_file))
    colour.intrinsics = with_size(read_intrinsic_matrix(colour_file), colour_size, colour_file, records[0].rgb);
  else if (colour_size == depth_size)
    colour.intrinsics = camera.depth;  // colour registered to depth
  else
    throw Error(colour_file, "not found, and the colour images differ in size from the depth images");
  colour.T_depth_colour = depth_from_colour(read_extrinsic(intrinsic / "extrinsic_color.txt"),
                                            read_extrinsic(intrinsic / "extrinsic_depth.txt"));
  if (!(colour.intrinsics == camera.depth) || !colour.T_depth_colour.matrix().isIdentity(1e-12)) camera.colour = colour;
  apply_yaml_camera(yaml, camera);
  return std::make_unique<LayoutDataset>("scannet", root, camera, std::move(records));
}

// ------------------------------------------------------------------ .sens

namespace {

// ScanNet's SensorData.h, version 4.
constexpr uint32_t kSensVersion = 4;
enum SensColour : int32_t { kColourRaw = 0, kColourPng = 1, kColourJpeg = 2 };
enum SensDepth : int32_t { kDepthRawUshort = 0, kDepthZlibUshort = 1 };
constexpr uint64_t kSensFrameHeaderBytes = 16 * 4 + 4 * 8;  // pose, 2 timestamps, 2 sizes

/// Bounds-checked little-endian reads from the .sens file.
class SensCursor {
 public:
  explicit SensCursor(const fs::path& file) : file_(file), in_(file, std::ios::binary) {
    if (!in_) throw Error(file, "cannot open");
    in_.seekg(0, std::ios::end);
    size_ = static_cast<uint64_t>(in_.tellg());
    in_.seekg(0);
  }
  template <class T>
  T read(const char* what) {
    T v{};
    need(sizeof v, what);
    in_.read(reinterpret_cast<char*>(&v), sizeof v);
    pos_ += sizeof v;
    return v;
  }
  std::vector<double> read_matrix(const char* what) {
    std::vector<double> m(16);
    for (double& v : m) v = read<float>(what);
    return m;
  }
  void skip(uint64_t n, const char* what) {
    need(n, what);
    pos_ += n;
    in_.seekg(static_cast<std::streamoff>(pos_));
  }
  uint64_t pos() const { return pos_; }
  uint64_t remaining() const { return size_ - pos_; }

 private:
  void need(uint64_t n, const char* what) {
    if (n > size_ - pos_ || !in_) throw Error(file_, std::string("truncated .sens file (in ") + what + ")");
  }
  fs::path file_;
  std::ifstream in_;
  uint64_t size_ = 0, pos_ = 0;
};

PinholeIntrinsics intrinsics_of(const std::vector<double>& m, uint32_t width, uint32_t height, const fs::path& file,
                                const char* which) {
  PinholeIntrinsics k{m[0], m[5], m[2], m[6], static_cast<int>(width), static_cast<int>(height)};
  if (!(k.fx > 0 && k.fy > 0 && std::isfinite(k.cx) && std::isfinite(k.cy)))
    throw Error(file, std::string("invalid ") + which + " intrinsics");
  return k;
}

uint32_t image_side(SensCursor& in, const fs::path& file, const char* what) {
  const uint32_t v = in.read<uint32_t>(what);
  if (v == 0 || v > 16384) throw Error(file, std::string("implausible ") + what + " " + std::to_string(v));
  return v;
}

struct SensFrame {
  uint64_t colour_offset = 0, colour_bytes = 0, depth_offset = 0, depth_bytes = 0;
};

class SensDataset : public DatasetReader {
 public:
  explicit SensDataset(const fs::path& file) {
    root_ = file;
    SensCursor in(file);
    read_header(in);
    read_frames(in);
  }
  std::string format() const override { return "scannet-sens"; }

  cv::Mat decode_depth(size_t i) const override {
    check_index(i);
    const std::string bytes = read_bytes(frames_[i].depth_offset, frames_[i].depth_bytes);
    const fs::path& where = records_[i].depth;
    cv::Mat raw(camera_.depth.height, camera_.depth.width, CV_16UC1);
    const size_t expected = raw.total() * raw.elemSize();
    if (depth_compression_ == kDepthRawUshort) {
      if (bytes.size() != expected) throw Error(where, "raw depth has " + std::to_string(bytes.size()) + " bytes, expected " + std::to_string(expected));
      std::memcpy(raw.data, bytes.data(), expected);
    } else {
      inflate(bytes, raw.data, expected, where);
    }
    return depth_units_to_metres(raw, camera_.depth_scale);
  }

  Frame decode(size_t i) const override {
    cv::Mat depth = decode_depth(i);
    const std::string bytes = read_bytes(frames_[i].colour_offset, frames_[i].colour_bytes);
    const fs::path& where = records_[i].rgb;
    cv::Mat rgb;
    if (colour_compression_ == kColourRaw) {
      const auto& k = camera_.colour_intrinsics();
      if (bytes.size() != size_t(k.width) * k.height * 3) throw Error(where, "raw colour has the wrong size");
      cv::cvtColor(cv::Mat(k.height, k.width, CV_8UC3, const_cast<char*>(bytes.data())), rgb, cv::COLOR_RGB2BGR);
    } else {
      rgb = decode_colour_bytes(bytes, where);
    }
    return make_frame(i, std::move(depth), std::move(rgb), where);
  }

 private:
  void read_header(SensCursor& in);
  void read_frames(SensCursor& in);
  std::string read_bytes(uint64_t offset, uint64_t n) const {
    std::ifstream in(root_, std::ios::binary);
    std::string bytes(n, '\0');
    in.seekg(static_cast<std::streamoff>(offset));
    in.read(bytes.data(), static_cast<std::streamsize>(n));
    if (!in) throw Error(root_, "cannot read frame data at byte " + std::to_string(offset));
    return bytes;
  }
  static void inflate(const std::string& in, void* out, size_t expected, const fs::path& where) {
    libdeflate_decompressor* d = libdeflate_alloc_decompressor();
    if (!d) throw Error(where, "out of memory");
    size_t actual = 0;
    const auto result = libdeflate_zlib_decompress(d, in.data(), in.size(), out, expected, &actual);
    libdeflate_free_decompressor(d);
    if (result != LIBDEFLATE_SUCCESS || actual != expected)
      throw Error(where, "corrupt zlib depth data (expected " + std::to_string(expected) + " bytes)");
  }

  int32_t colour_compression_ = kColourJpeg, depth_compression_ = kDepthZlibUshort;
  std::vector<SensFrame> frames_;
};

void SensDataset::read_header(SensCursor& in) {
  if (in.read<uint32_t>("version") != kSensVersion) throw Error(root_, "not a ScanNet .sens file (version 4)");
  const uint64_t name_length = in.read<uint64_t>("sensor name");
  if (name_length > 4096) throw Error(root_, "corrupt .sens header (sensor name length)");
  in.skip(name_length, "sensor name");
  const auto k_colour = in.read_matrix("colour intrinsics"), e_colour = in.read_matrix("colour extrinsics");
  const auto k_depth = in.read_matrix("depth intrinsics"), e_depth = in.read_matrix("depth extrinsics");
  colour_compression_ = in.read<int32_t>("colour compression");
  depth_compression_ = in.read<int32_t>("depth compression");
  if (colour_compression_ < kColourRaw || colour_compression_ > kColourJpeg)
    throw Error(root_, "unsupported colour compression " + std::to_string(colour_compression_));
  if (depth_compression_ != kDepthRawUshort && depth_compression_ != kDepthZlibUshort)
    throw Error(root_, "unsupported depth compression " + std::to_string(depth_compression_) + " (raw or zlib)");
  const uint32_t cw = image_side(in, root_, "colour width"), ch = image_side(in, root_, "colour height");
  const uint32_t dw = image_side(in, root_, "depth width"), dh = image_side(in, root_, "depth height");
  const float depth_shift = in.read<float>("depth shift");
  if (!(depth_shift > 0 && std::isfinite(depth_shift))) throw Error(root_, "invalid depth shift");
  CameraModel camera;
  camera.depth_scale = depth_shift;
  camera.depth = intrinsics_of(k_depth, dw, dh, root_, "depth");
  CameraModel::ColourCamera colour{intrinsics_of(k_colour, cw, ch, root_, "colour"),
                                   depth_from_colour(pose_from_rows(e_colour, root_.string() + ": colour extrinsics"),
                                                     pose_from_rows(e_depth, root_.string() + ": depth extrinsics"))};
  if (!(colour.intrinsics == camera.depth) || !colour.T_depth_colour.matrix().isIdentity(1e-12)) camera.colour = colour;
  set_camera(camera, root_.string());  // issue 44: the same camera check as every reader
}

void SensDataset::read_frames(SensCursor& in) {
  const uint64_t count = in.read<uint64_t>("frame count");
  if (count > in.remaining() / kSensFrameHeaderBytes) throw Error(root_, "corrupt .sens header (frame count)");
  std::vector<bool> invalid;
  for (uint64_t n = 0; n < count; ++n) {
    const std::vector<double> pose = in.read_matrix("frame pose");
    const uint64_t t_colour_us = in.read<uint64_t>("frame timestamp");
    in.read<uint64_t>("frame timestamp");
    SensFrame f;
    f.colour_bytes = in.read<uint64_t>("frame sizes");
    f.depth_bytes = in.read<uint64_t>("frame sizes");
    f.colour_offset = in.pos();
    in.skip(f.colour_bytes, "colour data");
    f.depth_offset = in.pos();
    in.skip(f.depth_bytes, "depth data");
    FrameRecord r;
    r.timestamp = t_colour_us > 0 ? t_colour_us * 1e-6 : n / kScanNetFrameRate;
    r.rgb = root_.string() + "#" + std::to_string(n) + ".color";
    r.depth = root_.string() + "#" + std::to_string(n) + ".depth";
    const bool bad = std::any_of(pose.begin(), pose.end(), [](double v) { return !std::isfinite(v); });
    if (!bad) r.gt_T_world_camera = pose_from_rows(pose, root_.string() + ": pose of frame " + std::to_string(n));
    records_.push_back(std::move(r));
    frames_.push_back(f);
    invalid.push_back(bad);
  }
  // Frames and records stay parallel.
  std::vector<SensFrame> kept;
  for (size_t i = 0; i < frames_.size(); ++i)
    if (!invalid[i]) kept.push_back(frames_[i]);
  frames_ = std::move(kept);
  skip_invalid_poses(records_, invalid, root_);
}

}  // namespace

std::unique_ptr<DatasetReader> open_scannet_sens(const fs::path& file) { return std::make_unique<SensDataset>(file); }

}  // namespace semap::io_detail
