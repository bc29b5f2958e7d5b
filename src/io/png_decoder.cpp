#include "io/png_decoder.hpp"

#include <libdeflate.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include <opencv2/imgproc.hpp>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace semap {
namespace {

using io_detail::read_be32;

// Rows are un-filtered in place; this much slack after the buffer lets the SSE2 paths load
// a whole 4-byte pixel at the end of a 3-byte-per-pixel row.
constexpr size_t kSlack = 16;

// ---- PNG filters (PNG spec section 9) --------------------------------------------------

inline uint8_t paeth_predictor(int a, int b, int c) {
  const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
  return static_cast<uint8_t>((pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c));
}

void unfilter_scalar(int filter, uint8_t* cur, const uint8_t* up, size_t n, size_t bpp) {
  switch (filter) {
    case 1:
      for (size_t i = bpp; i < n; ++i) cur[i] = static_cast<uint8_t>(cur[i] + cur[i - bpp]);
      break;
    case 2:
      for (size_t i = 0; i < n; ++i) cur[i] = static_cast<uint8_t>(cur[i] + up[i]);
      break;
    case 3:
      for (size_t i = 0; i < bpp; ++i) cur[i] = static_cast<uint8_t>(cur[i] + (up[i] >> 1));
      for (size_t i = bpp; i < n; ++i) cur[i] = static_cast<uint8_t>(cur[i] + ((cur[i - bpp] + up[i]) >> 1));
      break;
    case 4:
      for (size_t i = 0; i < bpp; ++i) cur[i] = static_cast<uint8_t>(cur[i] + up[i]);
      for (size_t i = bpp; i < n; ++i) cur[i] = static_cast<uint8_t>(cur[i] + paeth_predictor(cur[i - bpp], up[i], up[i - bpp]));
      break;
    default:
      break;
  }
}

#if defined(__SSE2__)
// Average and Paeth depend on the pixel to the left, so they run one pixel at a time with
// the channels in 16-bit lanes (the approach of libpng's SSE2 filters).
inline __m128i load_pixel(const uint8_t* p) {
  int32_t v;
  std::memcpy(&v, p, 4);
  return _mm_unpacklo_epi8(_mm_cvtsi32_si128(v), _mm_setzero_si128());
}
inline void store_pixel(uint8_t* p, __m128i v, size_t bpp) {
  const int32_t x = _mm_cvtsi128_si32(_mm_packus_epi16(v, _mm_setzero_si128()));
  std::memcpy(p, &x, bpp);
}
inline __m128i abs_epi16(__m128i x) { return _mm_max_epi16(x, _mm_sub_epi16(_mm_setzero_si128(), x)); }
inline __m128i select(__m128i mask, __m128i if_set, __m128i if_clear) {
  return _mm_or_si128(_mm_and_si128(mask, if_set), _mm_andnot_si128(mask, if_clear));
}

/// bpp 3 or 4: Average (3) and Paeth (4); false for the filters left to the scalar code.
bool unfilter_sse2(int filter, uint8_t* cur, const uint8_t* up, size_t n, size_t bpp) {
  if (filter != 3 && filter != 4) return false;
  const __m128i low_byte = _mm_set1_epi16(0xff);
  __m128i a = _mm_setzero_si128(), c = _mm_setzero_si128();
  for (size_t i = 0; i < n; i += bpp) {
    const __m128i b = load_pixel(up + i), x = load_pixel(cur + i);
    __m128i prediction;
    if (filter == 3) {
      prediction = _mm_srli_epi16(_mm_add_epi16(a, b), 1);
    } else {
      const __m128i pa = abs_epi16(_mm_sub_epi16(b, c)), pb = abs_epi16(_mm_sub_epi16(a, c));
      const __m128i pc = abs_epi16(_mm_sub_epi16(_mm_add_epi16(a, b), _mm_add_epi16(c, c)));
      // a when pa <= pb and pa <= pc, else b when pb <= pc, else c (the spec's tie order).
      const __m128i b_or_c = select(_mm_cmpgt_epi16(pb, pc), c, b);
      prediction = select(_mm_cmpgt_epi16(pa, _mm_min_epi16(pb, pc)), b_or_c, a);
      c = b;
    }
    a = _mm_and_si128(_mm_add_epi16(x, prediction), low_byte);
    store_pixel(cur + i, a, bpp);
  }
  return true;
}
#endif

void unfilter_row(int filter, uint8_t* cur, const uint8_t* up, size_t n, size_t bpp) {
#if defined(__SSE2__)
  if ((bpp == 3 || bpp == 4) && unfilter_sse2(filter, cur, up, n, bpp)) return;
#endif
  unfilter_scalar(filter, cur, up, n, bpp);
}

// ---- container ---------------------------------------------------------------------------

struct Header {
  uint32_t width = 0, height = 0;
  int bit_depth = 0, colour_type = 0;
};

bool supported(const Header& h) {
  return (h.colour_type == 0 && (h.bit_depth == 8 || h.bit_depth == 16)) ||
         ((h.colour_type == 2 || h.colour_type == 6) && h.bit_depth == 8);
}

bool crc_ok(const unsigned char* chunk, uint32_t length) {
  return libdeflate_crc32(0, chunk + 4, size_t{length} + 4) == read_be32(chunk + 8 + length);
}

struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

libdeflate_decompressor* thread_decompressor() {
  thread_local std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> decompressor(libdeflate_alloc_decompressor());
  return decompressor.get();
}

}  // namespace

std::optional<cv::Mat> decode_png_fast(std::string_view bytes) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const auto* b = reinterpret_cast<const unsigned char*>(bytes.data());
  const size_t n = bytes.size();
  if (n < 8 || std::memcmp(b, kSignature, 8) != 0) return std::nullopt;

  // Walk the chunks: IHDR, then IDATs, then IEND; anything else -> OpenCV.
  Header h;
  std::vector<uint8_t> compressed;
  bool seen_header = false, seen_end = false;
  for (size_t pos = 8; !seen_end;) {
    if (n - pos < 12) return std::nullopt;
    const uint32_t length = read_be32(b + pos);
    if (length > n - pos - 12) return std::nullopt;
    const unsigned char* chunk = b + pos;
    const std::string_view type(bytes.data() + pos + 4, 4);
    const unsigned char* data = chunk + 8;
    if (!seen_header) {
      if (type != "IHDR" || length != 13 || !crc_ok(chunk, length)) return std::nullopt;
      h.width = read_be32(data);
      h.height = read_be32(data + 4);
      h.bit_depth = data[8];
      h.colour_type = data[9];
      // compression 0, filter method 0, no interlacing
      if (data[10] != 0 || data[11] != 0 || data[12] != 0 || !supported(h)) return std::nullopt;
      // libpng's default limit is 1e6 per side; ours (as the container check's) 2^26 pixels.
      if (h.width == 0 || h.height == 0 || h.width > 1000000 || h.height > 1000000 ||
          uint64_t{h.width} * h.height > (uint64_t{1} << 26))
        return std::nullopt;
      seen_header = true;
    } else if (type == "IDAT") {
      if (!crc_ok(chunk, length)) return std::nullopt;
      compressed.insert(compressed.end(), data, data + length);
    } else if (type == "IEND") {
      if (length != 0 || !crc_ok(chunk, length)) return std::nullopt;  // libpng rejects a bad CRC even here
      seen_end = true;
    } else {
      // Only the plain IHDR, IDAT..., IEND layout of RGB-D frames: any other chunk (palette,
      // transparency, colour profiles, text) goes to libpng, which knows its rules.
      return std::nullopt;
    }
    pos += 12 + size_t{length};
  }
  if (compressed.empty()) return std::nullopt;

  const int channels = h.colour_type == 0 ? 1 : (h.colour_type == 2 ? 3 : 4);
  const size_t bpp = static_cast<size_t>(channels) * (h.bit_depth / 8);
  const size_t row_bytes = bpp * h.width, stride = row_bytes + 1;
  const size_t expected = stride * h.height;
  const std::unique_ptr<uint8_t[]> raw(new uint8_t[expected + kSlack]);  // not zero-filled: inflate writes it all
  std::memset(raw.get() + expected, 0, kSlack);
  size_t actual = 0;
  if (libdeflate_zlib_decompress(thread_decompressor(), compressed.data(), compressed.size(), raw.get(), expected,
                                 &actual) != LIBDEFLATE_SUCCESS ||
      actual != expected)
    return std::nullopt;

  const std::vector<uint8_t> zero_row(row_bytes + kSlack, 0);
  for (uint32_t y = 0; y < h.height; ++y) {
    uint8_t* row = raw.get() + y * stride;
    const int filter = row[0];
    if (filter > 4) return std::nullopt;
    unfilter_row(filter, row + 1, y == 0 ? zero_row.data() : row + 1 - stride, row_bytes, bpp);
  }
  // The un-filtered rows, each after its filter byte, as a strided view for OpenCV's
  // vectorised conversions into its own channel order.
  const int rows = static_cast<int>(h.height), cols = static_cast<int>(h.width);
  cv::Mat image;
  if (h.bit_depth == 16) {
    image.create(rows, cols, CV_16UC1);
    for (int y = 0; y < rows; ++y) {
      const uint8_t* in = raw.get() + y * stride + 1;
      uint16_t* out = image.ptr<uint16_t>(y);
      for (int x = 0; x < cols; ++x) out[x] = static_cast<uint16_t>((in[2 * x] << 8) | in[2 * x + 1]);
    }
  } else {
    const cv::Mat view(rows, cols, CV_MAKETYPE(CV_8U, channels), raw.get() + 1, stride);
    if (channels == 1) view.copyTo(image);
    else cv::cvtColor(view, image, channels == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_RGBA2BGRA);
  }
  return image;
}

}  // namespace semap
