// Image headers and decoding (io/image_header.cpp, io/image_io.cpp; issue 22): any input is
// refused with semap::Error or decoded; a decoded image has exactly the size its header
// declared (so the size cap checked on the header is the size that gets allocated), and no
// input makes a decoder allocate beyond the cap (libFuzzer's -rss_limit_mb catches that).
#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdlib>

#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "io/image_header.hpp"
#include "io/image_io.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  cv::Mat rgb(13, 17, CV_8UC3), grey16(9, 11, CV_16UC1), grey(7, 5, CV_8UC1);
  cv::randu(rgb, 0, 255);
  cv::randu(grey16, 0, 65535);
  cv::randu(grey, 0, 255);
  const std::pair<const char*, const cv::Mat*> seeds[] = {
      {".png", &rgb}, {".jpg", &rgb}, {".bmp", &rgb}, {".tiff", &rgb}, {".ppm", &rgb}, {".webp", &rgb},
      {".pgm", &grey}, {".tiff", &grey16}, {".png", &grey16}};
  int k = 0;
  for (const auto& [ext, image] : seeds) {
    std::vector<uchar> bytes;
    try {
      if (!cv::imencode(ext, *image, bytes)) continue;
    } catch (const cv::Exception&) {
      continue;
    }
    semap::fuzz::write_seed("seed" + std::to_string(k++) + ext, std::string(bytes.begin(), bytes.end()));
  }
  return 0;
}

namespace {
// The header's size against a successful decode: more pixels than the header declared means the
// cap was checked on a size smaller than the one allocated (a decompression bomb gets through).
// Fewer is safe: OpenCV decodes a truncated or odd file (a TIFF whose first directory is not
// the one it reads, a PNM with fewer rows) into less than the header promised.
void check_size(const semap::io_detail::ImageHeader& header, const cv::Mat& image) {
  if (static_cast<uint64_t>(image.cols) * static_cast<uint64_t>(image.rows) > header.width * header.height) std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  semap::io_detail::ImageHeader header;
  try {
    header = semap::io_detail::read_image_header(bytes, "fuzz.img");
  } catch (const semap::Error&) {
    return 0;
  }
  const auto path = semap::fuzz::input_file("fuzz.img", data, size);
  try {
    check_size(header, semap::read_colour_image(path));
  } catch (const semap::Error&) {
  }
  try {
    check_size(header, semap::read_label_image(path));
  } catch (const semap::Error&) {
  }
  return 0;
}
