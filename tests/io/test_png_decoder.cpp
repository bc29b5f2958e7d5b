// The fast PNG path must give exactly what OpenCV (libpng) gives, for every filter type and
// pixel layout it accepts, and must hand everything else (other layouts, corruption) back.
#include <libdeflate.h>

#include <opencv2/imgcodecs.hpp>
#include <functional>
#include <random>

#include "io/image_io.hpp"
#include "io/png_decoder.hpp"
#include "io/text_util.hpp"
#include "io_test_util.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

// ---- a small PNG writer with a chosen filter per row (OpenCV cannot choose filters) ----

void put_be32(std::string& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<char>((v >> s) & 0xff));
}

void put_chunk(std::string& out, const char* type, const std::string& data) {
  put_be32(out, static_cast<uint32_t>(data.size()));
  const std::string body = std::string(type, 4) + data;
  out += body;
  put_be32(out, libdeflate_crc32(0, body.data(), body.size()));
}

int paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

struct PngSpec {
  int bit_depth = 8, colour_type = 2, interlace = 0;
  bool trns = false;
};

/// Encodes `image` (CV_8UC1/3/4 or CV_16UC1, OpenCV channel order) with row y using filter
/// filter_of(y). The pixel bytes are written as PNG stores them (RGB order, big-endian).
std::string encode_png(const cv::Mat& image, const PngSpec& spec, const std::function<int(int)>& filter_of) {
  const int channels = image.channels();
  const size_t bpp = image.elemSize(), row_bytes = bpp * image.cols;
  std::string raw;
  std::vector<uint8_t> prev(row_bytes, 0), cur(row_bytes);
  for (int y = 0; y < image.rows; ++y) {
    const uint8_t* p = image.ptr<uint8_t>(y);
    for (int x = 0; x < image.cols; ++x)
      for (int c = 0; c < channels; ++c) {
        const int src = (channels >= 3 && c < 3) ? 2 - c : c;  // BGR(A) -> RGB(A)
        if (image.depth() == CV_16U) {
          const uint16_t v = reinterpret_cast<const uint16_t*>(p)[x * channels + src];
          cur[x * bpp + 2 * c] = static_cast<uint8_t>(v >> 8);
          cur[x * bpp + 2 * c + 1] = static_cast<uint8_t>(v & 0xff);
        } else {
          cur[x * bpp + c] = p[x * channels + src];
        }
      }
    const int filter = filter_of(y);
    raw.push_back(static_cast<char>(filter));
    for (size_t i = 0; i < row_bytes; ++i) {
      const int a = i >= bpp ? cur[i - bpp] : 0, b = prev[i], c = i >= bpp ? prev[i - bpp] : 0;
      const int pred = filter == 1 ? a : filter == 2 ? b : filter == 3 ? (a + b) / 2 : filter == 4 ? paeth(a, b, c) : 0;
      raw.push_back(static_cast<char>((cur[i] - pred) & 0xff));
    }
    prev = cur;
  }
  libdeflate_compressor* compressor = libdeflate_alloc_compressor(6);
  std::string compressed(libdeflate_zlib_compress_bound(compressor, raw.size()), '\0');
  compressed.resize(libdeflate_zlib_compress(compressor, raw.data(), raw.size(), compressed.data(), compressed.size()));
  libdeflate_free_compressor(compressor);

  std::string png("\x89PNG\r\n\x1a\n", 8), header;
  put_be32(header, static_cast<uint32_t>(image.cols));
  put_be32(header, static_cast<uint32_t>(image.rows));
  header += {static_cast<char>(spec.bit_depth), static_cast<char>(spec.colour_type), 0, 0, static_cast<char>(spec.interlace)};
  put_chunk(png, "IHDR", header);
  if (spec.trns) put_chunk(png, "tRNS", std::string(spec.colour_type == 0 ? 2 : 6, '\0'));
  // Split the stream over several IDAT chunks, as encoders do.
  for (size_t at = 0; at < compressed.size(); at += 1000) put_chunk(png, "IDAT", compressed.substr(at, 1000));
  put_chunk(png, "IEND", "");
  return png;
}

cv::Mat opencv_decode(const std::string& png) {
  return cv::imdecode(cv::Mat(1, static_cast<int>(png.size()), CV_8UC1, const_cast<char*>(png.data())), cv::IMREAD_UNCHANGED);
}

void expect_identical(const cv::Mat& fast, const cv::Mat& reference, const std::string& what) {
  ASSERT_FALSE(reference.empty()) << what;
  ASSERT_EQ(fast.type(), reference.type()) << what;
  ASSERT_EQ(fast.size(), reference.size()) << what;
  EXPECT_EQ(cv::norm(fast, reference, cv::NORM_INF), 0.0) << what;
}

cv::Mat random_image(int rows, int cols, int type, std::mt19937& rng, bool smooth) {
  cv::Mat m(rows, cols, type);
  const int channels = m.channels();
  std::uniform_int_distribution<int> noise(0, type == CV_16UC1 ? 65535 : 255), small(-3, 3);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols * channels; ++x) {
      const int v = smooth ? (40 * y + 7 * x + small(rng)) : noise(rng);
      if (m.depth() == CV_16U) m.ptr<uint16_t>(y)[x] = static_cast<uint16_t>(smooth ? (v * 97) & 0xffff : v);
      else m.ptr<uint8_t>(y)[x] = static_cast<uint8_t>(v & 0xff);
    }
  return m;
}

struct Layout {
  int type, colour_type, bit_depth;
};
const Layout kLayouts[] = {{CV_8UC1, 0, 8}, {CV_16UC1, 0, 16}, {CV_8UC3, 2, 8}, {CV_8UC4, 6, 8}};

TEST(PngDecoder, EveryFilterAndLayoutMatchesOpenCv) {
  std::mt19937 rng(7);
  const cv::Size sizes[] = {{1, 1}, {1, 9}, {7, 3}, {33, 17}, {160, 120}};
  for (const Layout& layout : kLayouts)
    for (const cv::Size size : sizes)
      for (bool smooth : {false, true})
        for (int filter = 0; filter <= 5; ++filter) {  // 5: rows cycle through all five
          const cv::Mat image = random_image(size.height, size.width, layout.type, rng, smooth);
          const std::string png = encode_png(image, {layout.bit_depth, layout.colour_type},
                                             [&](int y) { return filter == 5 ? y % 5 : filter; });
          const std::string what = "type " + std::to_string(layout.type) + " size " + std::to_string(size.width) + "x" +
                                   std::to_string(size.height) + " filter " + std::to_string(filter);
          const auto fast = decode_png_fast(png);
          ASSERT_TRUE(fast.has_value()) << what;
          expect_identical(*fast, opencv_decode(png), what);
          EXPECT_EQ(cv::norm(*fast, image, cv::NORM_INF), 0.0) << what;
        }
}

TEST(PngDecoder, OpenCvEncodedImagesMatch) {
  std::mt19937 rng(11);
  for (const Layout& layout : kLayouts)
    for (int level : {0, 1, 6, 9}) {
      const cv::Mat image = random_image(97, 131, layout.type, rng, level % 2 == 1);
      std::vector<uchar> png;
      ASSERT_TRUE(cv::imencode(".png", image, png, {cv::IMWRITE_PNG_COMPRESSION, level}));
      const std::string bytes(png.begin(), png.end());
      const auto fast = decode_png_fast(bytes);
      ASSERT_TRUE(fast.has_value()) << "type " << layout.type << " level " << level;
      expect_identical(*fast, opencv_decode(bytes), "opencv-encoded");
    }
}

TEST(PngDecoder, DatasetFramesMatchOpenCv) {
  SEMAP_REQUIRE_DATA(tum, "tum_fr1_rpy");
  size_t checked = 0;
  for (const char* folder : {"rgb", "depth"}) {
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(tum / folder)) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (size_t i = 0; i < std::min<size_t>(files.size(), 5); ++i) {
      const std::string bytes = io_detail::read_file_bytes(files[i]);
      const auto fast = decode_png_fast(bytes);
      ASSERT_TRUE(fast.has_value()) << files[i];
      expect_identical(*fast, opencv_decode(bytes), files[i].string());
      ++checked;
    }
  }
  EXPECT_EQ(checked, 10u);
}

TEST(PngDecoder, OtherLayoutsAreLeftToOpenCv) {
  std::mt19937 rng(3);
  const cv::Mat grey = random_image(8, 8, CV_8UC1, rng, true);
  const auto plain = [](int) { return 1; };
  EXPECT_TRUE(decode_png_fast(encode_png(grey, {8, 0}, plain)).has_value());
  EXPECT_FALSE(decode_png_fast(encode_png(grey, {8, 0, 1}, plain)).has_value()) << "interlaced";
  EXPECT_FALSE(decode_png_fast(encode_png(grey, {8, 3}, plain)).has_value()) << "palette";
  EXPECT_FALSE(decode_png_fast(encode_png(grey, {8, 0, 0, true}, plain)).has_value()) << "tRNS";
  const cv::Mat rgb16 = random_image(8, 8, CV_16UC3, rng, true);
  EXPECT_FALSE(decode_png_fast(encode_png(rgb16, {16, 2}, plain)).has_value()) << "16-bit RGB";
  EXPECT_FALSE(decode_png_fast("not a png").has_value());
}

TEST(PngDecoder, CorruptionIsRejectedAndReportedByTheReader) {
  std::mt19937 rng(5);
  const cv::Mat image = random_image(40, 30, CV_8UC3, rng, true);
  const std::string png = encode_png(image, {8, 2}, [](int y) { return y % 5; });
  ASSERT_TRUE(decode_png_fast(png).has_value());
  const size_t idat = png.find("IDAT");
  ASSERT_NE(idat, std::string::npos);

  std::string flipped = png;
  flipped[idat + 40] = static_cast<char>(flipped[idat + 40] ^ 0x5a);  // CRC no longer matches
  EXPECT_FALSE(decode_png_fast(flipped).has_value());

  // Valid CRCs around a damaged zlib stream: the inflate check catches it.
  std::string bad_stream = png;
  const uint32_t length = (uint8_t(png[idat - 4]) << 24) | (uint8_t(png[idat - 3]) << 16) | (uint8_t(png[idat - 2]) << 8) | uint8_t(png[idat - 1]);
  for (size_t i = 8; i < 24; ++i) bad_stream[idat + 4 + i] = static_cast<char>(0xff);
  const uint32_t crc = libdeflate_crc32(0, bad_stream.data() + idat, length + 4);
  for (int k = 0; k < 4; ++k) bad_stream[idat + 4 + length + k] = static_cast<char>((crc >> (24 - 8 * k)) & 0xff);
  EXPECT_FALSE(decode_png_fast(bad_stream).has_value());

  // The reader still turns such files into a one-line error naming the file.
  test::TempDir dir;
  for (const auto& [name, bytes] : {std::pair{"flipped.png", flipped}, std::pair{"stream.png", bad_stream}}) {
    test::write_bytes(dir / name, bytes);
    const std::filesystem::path file = dir / name;  // clang 14 cannot capture a structured binding
    EXPECT_TRUE(test::throws_naming([&] { read_colour_image(file); }, name)) << name;
  }
}

}  // namespace
}  // namespace semap
