// Fast PNG decoder (src/io/png_decoder.cpp), differential: whatever it accepts must decode
// exactly as OpenCV (libpng) decodes it; anything else it must hand back, never crash.
#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>

#include <libdeflate.h>

#include "fuzz/fuzz_util.hpp"
#include "io/png_decoder.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  cv::Mat rgb(9, 7, CV_8UC3), grey16(5, 11, CV_16UC1), rgba(4, 3, CV_8UC4);
  cv::randu(rgb, 0, 255);
  cv::randu(grey16, 0, 65535);
  cv::randu(rgba, 0, 255);
  for (const auto& [name, image] : {std::pair{"rgb.png", rgb}, std::pair{"grey16.png", grey16}, std::pair{"rgba.png", rgba}}) {
    std::vector<uchar> png;
    cv::imencode(".png", image, png);
    semap::fuzz::write_seed(name, std::string(png.begin(), png.end()));
  }
  std::string scanlines = {'s', 23, 17, 2};  // 24x18 RGB, rows cycling through the filters
  for (int row = 0; row < 18; ++row) {
    scanlines.push_back(static_cast<char>(row % 5));
    for (int i = 0; i < 24 * 3; ++i) scanlines.push_back(static_cast<char>(row * 7 + i * 3));
  }
  semap::fuzz::write_seed("scanlines.bin", scanlines);
  return 0;
}

// Random mutations almost never keep a chunk's CRC, so the CRCs are rewritten before decoding
// (as fuzz_map appends its checksum): the fuzzer then reaches the zlib stream and the filters.
std::string with_valid_crcs(const uint8_t* data, size_t size) {
  std::string png(reinterpret_cast<const char*>(data), size);
  for (size_t pos = 8; pos + 12 <= png.size();) {
    const auto* p = reinterpret_cast<const uint8_t*>(png.data() + pos);
    const size_t length = (size_t{p[0]} << 24) | (size_t{p[1]} << 16) | (size_t{p[2]} << 8) | p[3];
    if (length > png.size() - pos - 12) break;
    const uint32_t crc = libdeflate_crc32(0, png.data() + pos + 4, length + 4);
    for (int k = 0; k < 4; ++k) png[pos + 8 + length + k] = static_cast<char>((crc >> (24 - 8 * k)) & 0xff);
    pos += 12 + length;
  }
  return png;
}

void put_be32(std::string& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((v >> shift) & 0xff));
}
void put_chunk(std::string& out, const char* type, const std::string& data) {
  put_be32(out, static_cast<uint32_t>(data.size()));
  out += std::string(type, 4) + data;
  put_be32(out, libdeflate_crc32(0, out.data() + out.size() - data.size() - 4, data.size() + 4));
}

// Mutated zlib streams fail their Adler-32 check too, so inputs that do not start like a PNG
// are taken as raw filtered scanlines (header: width, height, layout) wrapped into a valid PNG:
// they exercise every filter on every layout, including bad filter bytes.
std::string png_from_scanlines(const uint8_t* data, size_t size) {
  static const uint8_t kLayouts[4][2] = {{8, 0}, {16, 0}, {8, 2}, {8, 6}};  // bit depth, colour type
  if (size < 4) return {};
  const uint32_t width = 1 + data[1] % 64, height = 1 + data[2] % 64;
  const uint8_t* layout = kLayouts[data[3] % 4];
  const size_t bpp = (layout[0] / 8) * (layout[1] == 0 ? 1 : layout[1] == 2 ? 3 : 4);
  std::string raw(height * (1 + width * bpp), '\0');
  std::copy(data + 4, data + std::min(size, 4 + raw.size()), raw.begin());
  for (size_t row = 0; row < height; ++row) raw[row * (1 + width * bpp)] = static_cast<char>(raw[row * (1 + width * bpp)] % 6);
  libdeflate_compressor* compressor = libdeflate_alloc_compressor(1);
  std::string compressed(libdeflate_zlib_compress_bound(compressor, raw.size()), '\0');
  compressed.resize(libdeflate_zlib_compress(compressor, raw.data(), raw.size(), compressed.data(), compressed.size()));
  libdeflate_free_compressor(compressor);
  std::string png("\x89PNG\r\n\x1a\n", 8), header;
  put_be32(header, width);
  put_be32(header, height);
  header += {static_cast<char>(layout[0]), static_cast<char>(layout[1]), 0, 0, 0};
  put_chunk(png, "IHDR", header);
  put_chunk(png, "IDAT", compressed);
  put_chunk(png, "IEND", "");
  return png;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* raw, size_t raw_size) {
  const bool scanlines = raw_size > 0 && raw[0] != 0x89;  // 0x89: the PNG signature's first byte
  const std::string png = scanlines ? png_from_scanlines(raw, raw_size) : with_valid_crcs(raw, raw_size);
  const auto* data = reinterpret_cast<const uint8_t*>(png.data());
  const size_t size = png.size();
  if (size == 0) return 0;
  const std::string_view bytes(png);
  const auto fast = semap::decode_png_fast(bytes);
  if (!fast) return 0;
  const cv::Mat reference =
      cv::imdecode(cv::Mat(1, static_cast<int>(size), CV_8UC1, const_cast<uint8_t*>(data)), cv::IMREAD_UNCHANGED);
  if (reference.empty() || reference.type() != fast->type() || reference.size() != fast->size() ||
      cv::norm(reference, *fast, cv::NORM_INF) != 0)
    std::abort();  // a decode that differs from libpng's is a finding
  return 0;
}
