#include "io/image_io.hpp"

#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "io/image_header.hpp"
#include "io/png_decoder.hpp"
#include "io/text_util.hpp"

namespace semap {

namespace {

// Larger images are treated as corrupt or hostile headers (never needed for RGB-D frames):
// 2^26 pixels (8192x8192) decode to at most 512 MiB even as 16-bit RGBA.
constexpr uint64_t kMaxPixels = uint64_t{1} << 26;

// The declared size of every format, before any decoder allocates (io/image_header.hpp).
void check_declared_size(const std::filesystem::path& path, const std::string& bytes) {
  const io_detail::ImageHeader header = io_detail::read_image_header(bytes, path.string());
  if (header.width > kMaxPixels || header.height > kMaxPixels || header.width * header.height > kMaxPixels)
    throw Error(path, std::string(header.format) + " header declares " + std::to_string(header.width) + "x" +
                          std::to_string(header.height) + " pixels, more than the limit of " +
                          std::to_string(kMaxPixels) + " (8192x8192): not decoded (corrupt or hostile header?)");
}

using io_detail::read_be32;

// OpenCV/libjpeg decode truncated JPEGs with a grey fill and only a warning, and libpng may
// decode a PNG cut after its last IDAT; so the container structure is checked first.
void check_container(const std::filesystem::path& path, const std::string& bytes) {
  const auto* b = reinterpret_cast<const unsigned char*>(bytes.data());
  const size_t n = bytes.size();
  static const unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n >= 8 && std::memcmp(b, kPng, 8) == 0) {
    size_t pos = 8;
    bool first = true;
    while (true) {
      if (n - pos < 12) throw Error(path, "truncated PNG (no IEND chunk)");
      const uint32_t length = read_be32(b + pos);
      const std::string type(bytes.data() + pos + 4, 4);
      if (length > n - pos - 12) throw Error(path, "truncated PNG (chunk '" + type + "' runs past the end)");
      if (first) {
        if (type != "IHDR" || length < 13) throw Error(path, "corrupt PNG (no IHDR)");
        first = false;
      }
      pos += 12 + length;
      if (type == "IEND") return;
    }
  }
  if (n >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) {
    // End-of-image marker, allowing a little padding after it.
    for (size_t i = n; i >= 2 && n - i < 64; --i)
      if (b[i - 2] == 0xFF && b[i - 1] == 0xD9) return;
    throw Error(path, "truncated JPEG (no end-of-image marker)");
  }
}

cv::Mat decode_bytes(const std::filesystem::path& path, const std::string& bytes) {
  if (bytes.empty()) throw Error(path, "empty image file");
  check_declared_size(path, bytes);
  check_container(path, bytes);
  if (auto fast = decode_png_fast(bytes)) return std::move(*fast);  // the common RGB-D layouts
  cv::Mat image;
  try {
    image = cv::imdecode(cv::Mat(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data())),
                         cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw Error(path, std::string("cannot decode image: ") + e.what());
  }
  if (image.empty()) throw Error(path, "cannot decode image (corrupt, truncated or unsupported format)");
  return image;
}

cv::Mat decode(const std::filesystem::path& path) {
  return decode_bytes(path, io_detail::read_file_bytes(path, kMaxImageFileBytes, "image"));
}

std::string size_text(cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }

void check_size(const std::filesystem::path& path, const cv::Mat& image, cv::Size expected, const char* what) {
  if (expected.area() > 0 && image.size() != expected)
    throw Error(path, std::string(what) + " is " + size_text(image.size()) + ", expected " + size_text(expected));
}

std::vector<uchar> encode(const std::filesystem::path& path, const cv::Mat& image) {
  std::string ext = path.extension().string();
  if (ext.empty()) throw Error(path, "no file extension to choose an image format");
  std::vector<uchar> buffer;
  try {
    if (!cv::imencode(ext, image, buffer)) throw Error(path, "cannot encode image");
  } catch (const cv::Exception& e) {
    throw Error(path, std::string("cannot encode image: ") + e.what());
  }
  return buffer;
}

}  // namespace

cv::Mat decode_image_bytes(const std::string& bytes, const std::filesystem::path& source) {
  return decode_bytes(source, bytes);
}

cv::Mat decode_colour_bytes(const std::string& bytes, const std::filesystem::path& source) {
  return to_bgr(source, decode_bytes(source, bytes));
}

cv::Mat read_colour_image(const std::filesystem::path& path) { return to_bgr(path, decode(path)); }

cv::Mat to_bgr(const std::filesystem::path& path, cv::Mat image) {
  if (image.depth() != CV_8U) throw Error(path, "colour image is not 8-bit");
  if (image.channels() == 3) return image;
  cv::Mat bgr;
  if (image.channels() == 4) cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
  else if (image.channels() == 1) cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  else throw Error(path, "colour image with " + std::to_string(image.channels()) + " channels");
  return bgr;
}

cv::Mat read_depth_image(const std::filesystem::path& path, double depth_scale, cv::Size expected_size) {
  if (!(depth_scale > 0)) throw Error(path, "depth scale must be positive");
  const cv::Mat raw = decode(path);
  if (raw.channels() != 1) throw Error(path, "depth image has " + std::to_string(raw.channels()) + " channels, expected 1");
  if (raw.depth() == CV_8U || raw.depth() == CV_8S) throw Error(path, "8-bit depth image, expected 16-bit");
  if (raw.depth() != CV_16U) throw Error(path, "depth image is not 16-bit unsigned");
  check_size(path, raw, expected_size, "depth image");
  return depth_units_to_metres(raw, depth_scale);
}

cv::Mat depth_units_to_metres(const cv::Mat& raw, double depth_scale) {
  CV_Assert(raw.type() == CV_16UC1 && depth_scale > 0);
  cv::Mat depth(raw.size(), CV_32FC1);
  const float inv_scale = static_cast<float>(1.0 / depth_scale);
  for (int r = 0; r < raw.rows; ++r) {
    const uint16_t* in = raw.ptr<uint16_t>(r);
    float* out = depth.ptr<float>(r);
    for (int c = 0; c < raw.cols; ++c) out[c] = (in[c] == 0 || in[c] == 65535) ? 0.0f : in[c] * inv_scale;
  }
  return depth;
}

cv::Mat read_label_image(const std::filesystem::path& path, cv::Size expected_size) {
  const cv::Mat raw = decode(path);
  if (raw.channels() != 1) throw Error(path, "label image has " + std::to_string(raw.channels()) + " channels, expected 1");
  check_size(path, raw, expected_size, "label image");
  if (raw.depth() == CV_16U) return raw;
  if (raw.depth() != CV_8U) throw Error(path, "label image must be 8- or 16-bit unsigned");
  cv::Mat out;
  raw.convertTo(out, CV_16U);
  return out;
}

void write_depth_image(const std::filesystem::path& path, const cv::Mat& depth_m, double depth_scale) {
  if (depth_m.empty() || depth_m.channels() != 1 || (depth_m.depth() != CV_32F && depth_m.depth() != CV_64F))
    throw Error(path, "write_depth_image expects a CV_32FC1 or CV_64FC1 depth image");
  if (!(depth_scale > 0)) throw Error(path, "depth scale must be positive");
  cv::Mat metres;
  depth_m.convertTo(metres, CV_64F);
  cv::Mat raw(depth_m.size(), CV_16UC1);
  for (int r = 0; r < raw.rows; ++r) {
    const double* in = metres.ptr<double>(r);
    uint16_t* out = raw.ptr<uint16_t>(r);
    for (int c = 0; c < raw.cols; ++c) {
      const double v = std::round(in[c] * depth_scale);
      out[c] = (std::isfinite(v) && v > 0 && v < 65535) ? static_cast<uint16_t>(v) : 0;  // 65535 = invalid too
    }
  }
  write_image(path, raw);
}

void write_image(const std::filesystem::path& path, const cv::Mat& image) {
  if (image.empty()) throw Error(path, "refusing to write an empty image");
  const auto buffer = encode(path, image);
  write_file_atomic(path, std::string(buffer.begin(), buffer.end()));
}

}  // namespace semap
