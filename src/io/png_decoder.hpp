#pragma once
// Fast decoding of the PNG layouts RGB-D datasets use (TUM, 7-Scenes, our synthetic scenes).
// PNG decoding was the largest single CPU cost of a `semap run` (libpng + zlib: about 15 ms
// per 640x480 RGB-D pair); libdeflate inflates about 3x faster and the Paeth/Average
// un-filtering runs on SSE2. The result is identical to cv::imdecode(IMREAD_UNCHANGED).
#include <cstdint>
#include <optional>
#include <string_view>

#include <opencv2/core.hpp>

namespace semap {

namespace io_detail {
/// A big-endian 32-bit field (PNG chunk lengths, image sizes, CRCs).
inline uint32_t read_be32(const unsigned char* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3];
}
}  // namespace io_detail

/// Decodes 8-bit grey (CV_8UC1), 16-bit grey (CV_16UC1), 8-bit RGB (CV_8UC3, BGR order) and
/// 8-bit RGBA (CV_8UC4, BGRA) non-interlaced PNGs made of IHDR, IDAT... and IEND chunks
/// with intact CRCs and zlib streams. Returns nullopt for anything else (other layouts or
/// chunks, any corruption), so the caller can hand those to OpenCV, which decodes or rejects them.
std::optional<cv::Mat> decode_png_fast(std::string_view bytes);

}  // namespace semap
