#pragma once
// Image headers read before any decoding (issue 22): a 349-byte JPEG declaring 16384x16384
// pixels, or a 1 KB run-length BMP, decodes to gigabytes. Every format OpenCV would be handed
// has its declared size read here first; a format not listed is refused, so no decoder runs on
// a header nobody checked.
#include <cstdint>
#include <string>
#include <string_view>

namespace semap::io_detail {

struct ImageHeader {
  const char* format = "";  ///< "PNG", "JPEG", "BMP", "TIFF", "PNM", "WebP"
  uint64_t width = 0, height = 0;
};

/// Format and declared size from the file's first bytes. Throws semap::Error(source, ...) for
/// an unsupported format, a header cut short, or a zero size.
ImageHeader read_image_header(std::string_view bytes, const std::string& source);

}  // namespace semap::io_detail
