#include "io/image_header.hpp"

#include <cctype>
#include <cstring>
#include <optional>
#include <set>

#include "semap/core/error.hpp"

namespace semap::io_detail {

namespace {

/// Bounds-checked little/big-endian field reads over the file's bytes.
class Bytes {
 public:
  explicit Bytes(std::string_view b) : b_(b) {}
  size_t size() const { return b_.size(); }
  bool has(size_t pos, size_t n) const { return pos <= b_.size() && n <= b_.size() - pos; }
  uint8_t u8(size_t pos) const { return has(pos, 1) ? static_cast<uint8_t>(b_[pos]) : 0; }
  uint32_t be16(size_t p) const { return (uint32_t{u8(p)} << 8) | u8(p + 1); }
  uint32_t le16(size_t p) const { return (uint32_t{u8(p + 1)} << 8) | u8(p); }
  uint32_t be32(size_t p) const { return (be16(p) << 16) | be16(p + 2); }
  uint32_t le32(size_t p) const { return (le16(p + 2) << 16) | le16(p); }
  bool starts_with(std::string_view magic, size_t pos = 0) const { return has(pos, magic.size()) && b_.substr(pos, magic.size()) == magic; }

 private:
  std::string_view b_;
};

[[noreturn]] void bad(const std::string& source, const char* format, const std::string& why) {
  throw Error(source, std::string("corrupt ") + format + " header: " + why);
}

ImageHeader png_header(const Bytes& b, const std::string& source) {
  if (!b.has(8, 24) || !b.starts_with("IHDR", 12)) bad(source, "PNG", "no IHDR chunk");
  return {"PNG", b.be32(16), b.be32(20)};
}

// Markers up to the first start-of-frame (SOF0..SOF15 without DHT C4, JPG C8, DAC CC).
ImageHeader jpeg_header(const Bytes& b, const std::string& source) {
  size_t pos = 2;
  while (true) {
    while (b.u8(pos) == 0xFF && b.u8(pos + 1) == 0xFF) ++pos;  // fill bytes
    if (!b.has(pos, 4)) bad(source, "JPEG", "no frame header (SOF) before the end of the file");
    if (b.u8(pos) != 0xFF) bad(source, "JPEG", "marker expected at byte " + std::to_string(pos));
    const uint8_t marker = b.u8(pos + 1);
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) {
      pos += 2;  // standalone markers carry no length
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) bad(source, "JPEG", "image data before any frame header (SOF)");
    const uint32_t length = b.be16(pos + 2);
    if (length < 2) bad(source, "JPEG", "segment length below 2");
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      if (length < 8 || !b.has(pos + 2, 8)) bad(source, "JPEG", "frame header cut short");
      return {"JPEG", b.be16(pos + 7), b.be16(pos + 5)};  // SOF: precision, height, width
    }
    pos += 2 + length;
  }
}

ImageHeader bmp_header(const Bytes& b, const std::string& source) {
  if (!b.has(14, 12)) bad(source, "BMP", "cut short");
  const uint32_t dib = b.le32(14);
  if (dib == 12) return {"BMP", b.le16(18), b.le16(20)};  // BITMAPCOREHEADER
  if (dib < 40 || !b.has(14, 16)) bad(source, "BMP", "unknown info header size " + std::to_string(dib));
  const auto width = static_cast<int32_t>(b.le32(18)), height = static_cast<int32_t>(b.le32(22));
  if (width <= 0 || height == INT32_MIN) bad(source, "BMP", "invalid width " + std::to_string(width));
  return {"BMP", static_cast<uint64_t>(width), static_cast<uint64_t>(height < 0 ? -int64_t{height} : height)};
}

// First image file directory: ImageWidth (256), ImageLength (257), TileWidth/TileLength (322/323).
ImageHeader tiff_header(const Bytes& b, const std::string& source) {
  const bool little = b.u8(0) == 'I';
  const auto u16 = [&](size_t p) { return little ? b.le16(p) : b.be16(p); };
  const auto u32 = [&](size_t p) { return little ? b.le32(p) : b.be32(p); };
  const uint32_t ifd = u32(4);
  if (!b.has(ifd, 2)) bad(source, "TIFF", "first directory outside the file");
  const uint32_t entries = u16(ifd);
  if (!b.has(ifd + 2, size_t{entries} * 12)) bad(source, "TIFF", "directory cut short");
  uint64_t width = 0, height = 0, tile_w = 0, tile_h = 0, samples = 1;
  std::set<uint32_t> seen;
  for (uint32_t k = 0; k < entries; ++k) {
    const size_t e = ifd + 2 + size_t{k} * 12;
    const uint32_t tag = u16(e), type = u16(e + 2);
    // libtiff keeps the first of repeated tags, a reader could take the last: a repeated size
    // tag is ambiguous and refused (fuzz_image: widths 11 then 5, decoded at 11).
    const bool size_tag = tag == 256 || tag == 257 || tag == 322 || tag == 323 || tag == 277;
    if (size_tag && !seen.insert(tag).second) bad(source, "TIFF", "tag " + std::to_string(tag) + " appears twice");
    const uint64_t value = type == 3 ? u16(e + 8) : type == 4 ? u32(e + 8) : 0;  // SHORT / LONG
    if (tag == 256) width = value;
    else if (tag == 257) height = value;
    else if (tag == 322) tile_w = value;
    else if (tag == 323) tile_h = value;
    else if (tag == 277) samples = value;
  }
  if (samples == 0 || samples > 4) bad(source, "TIFF", std::to_string(samples) + " samples per pixel (1 to 4 are read)");
  if (tile_w * tile_h > width * height + (uint64_t{1} << 20))
    bad(source, "TIFF", "tiles of " + std::to_string(tile_w) + "x" + std::to_string(tile_h) + " larger than the image");
  return {"TIFF", width, height};
}

// P1..P6: magic, then width and height as decimal tokens with '#' comments between, parsed
// as OpenCV's PxM reader does.
ImageHeader pnm_header(std::string_view text, const std::string& source) {
  size_t pos = 2;
  const auto token = [&]() -> std::optional<uint64_t> {
    while (pos < text.size()) {
      if (std::isspace(static_cast<unsigned char>(text[pos]))) ++pos;
      // A comment ends at '\n' or '\r', as in OpenCV's ReadNumber (fuzz_image found "# ..\r5\n"
      // read as no width here where OpenCV decoded width 5).
      else if (text[pos] == '#') while (pos < text.size() && text[pos] != '\n' && text[pos] != '\r') ++pos;
      else break;
    }
    uint64_t v = 0;
    size_t digits = 0;
    while (pos < text.size() && std::isdigit(static_cast<unsigned char>(text[pos])) && digits < 12)
      v = v * 10 + static_cast<uint64_t>(text[pos++] - '0'), ++digits;
    if (digits == 0) return std::nullopt;
    // OpenCV's reader consumes the byte ending a number, whatever it is: "2#1" is 2 then 1
    // (fuzz_image found the header read as 2x5 where OpenCV decoded 2x1).
    if (pos < text.size()) ++pos;
    return v;
  };
  const auto width = token(), height = token();
  if (!width || !height) bad(source, "PNM", "no width and height");
  return {"PNM", *width, *height};
}

ImageHeader webp_header(const Bytes& b, const std::string& source) {
  if (b.starts_with("VP8 ", 12)) {
    if (!b.has(20, 10) || b.u8(23) != 0x9D || b.u8(24) != 0x01 || b.u8(25) != 0x2A) bad(source, "WebP", "no VP8 frame header");
    return {"WebP", b.le16(26) & 0x3FFF, b.le16(28) & 0x3FFF};
  }
  if (b.starts_with("VP8L", 12)) {
    if (!b.has(20, 5) || b.u8(20) != 0x2F) bad(source, "WebP", "no VP8L signature");
    const uint32_t bits = b.le32(21);
    return {"WebP", (bits & 0x3FFF) + 1, ((bits >> 14) & 0x3FFF) + 1};
  }
  if (b.starts_with("VP8X", 12)) {
    if (!b.has(24, 6)) bad(source, "WebP", "extended header cut short");
    const auto u24 = [&](size_t p) { return uint64_t{b.u8(p)} | uint64_t{b.u8(p + 1)} << 8 | uint64_t{b.u8(p + 2)} << 16; };
    return {"WebP", u24(24) + 1, u24(27) + 1};
  }
  bad(source, "WebP", "unknown chunk after the RIFF header");
}

}  // namespace

ImageHeader read_image_header(std::string_view bytes, const std::string& source) {
  const Bytes b(bytes);
  ImageHeader header;
  if (b.starts_with("\x89PNG\r\n\x1a\n")) header = png_header(b, source);
  else if (b.starts_with("\xFF\xD8\xFF")) header = jpeg_header(b, source);
  else if (b.starts_with("BM")) header = bmp_header(b, source);
  else if (b.starts_with(std::string_view("II*\0", 4)) || b.starts_with(std::string_view("MM\0*", 4))) header = tiff_header(b, source);
  else if (b.size() >= 3 && bytes[0] == 'P' && bytes[1] >= '1' && bytes[1] <= '6' && std::isspace(static_cast<unsigned char>(bytes[2])))
    header = pnm_header(bytes, source);
  else if (b.starts_with("RIFF") && b.starts_with("WEBP", 8)) header = webp_header(b, source);
  else
    throw Error(source, "unsupported image format (PNG, JPEG, BMP, TIFF, PNM and WebP are read)");
  if (header.width == 0 || header.height == 0)
    throw Error(source, std::string("corrupt ") + header.format + " header: declares a size of " +
                            std::to_string(header.width) + "x" + std::to_string(header.height));
  return header;
}

}  // namespace semap::io_detail
