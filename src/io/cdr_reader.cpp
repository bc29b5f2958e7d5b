// CDR decoding (cdr_reader.hpp) and the sensor_msgs/msg types of ROS 2 (rosidl definitions of
// Humble/Jazzy: std_msgs/Header, sensor_msgs/Image, CompressedImage, CameraInfo).
#include "io/cdr_reader.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

#include "semap/core/error.hpp"

namespace semap::io_detail {

namespace {
constexpr size_t kEncapsulationBytes = 4;
std::string num(size_t v) { return std::to_string(v); }
}  // namespace

CdrReader::CdrReader(std::span<const uint8_t> message, std::string where) : where_(std::move(where)) {
  if (message.size() < kEncapsulationBytes)
    throw Error(where_, "CDR message of " + num(message.size()) + " bytes has no encapsulation header");
  // Representation id (big-endian on the wire): 0x0000 CDR_BE, 0x0001 CDR_LE (XCDR1).
  if (message[0] != 0 || message[1] > 1)
    throw Error(where_, "CDR encapsulation " + num(message[0]) + " " + num(message[1]) +
                            " is not plain CDR (00 00 or 00 01; XCDR2 is not supported)");
  big_endian_ = message[1] == 0;
  body_ = message.subspan(kEncapsulationBytes);
}

void CdrReader::align(size_t n) {
  const size_t padded = (pos_ + n - 1) / n * n;
  if (padded > body_.size()) throw Error(where_, "CDR message ends at byte " + num(body_.size() + kEncapsulationBytes) + " (truncated)");
  pos_ = padded;
}

const uint8_t* CdrReader::take(size_t n, const char* what) {
  if (n > body_.size() - pos_)
    throw Error(where_, std::string("CDR ") + what + " of " + num(n) + " bytes at byte " + num(pos_ + kEncapsulationBytes) +
                            " runs past the end of the " + num(body_.size() + kEncapsulationBytes) + "-byte message");
  const uint8_t* p = body_.data() + pos_;
  pos_ += n;
  return p;
}

template <class T>
T CdrReader::number(const char* what) {
  align(std::min(sizeof(T), size_t{8}));
  uint8_t b[sizeof(T)];
  std::memcpy(b, take(sizeof(T), what), sizeof(T));
  if (big_endian_ != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

uint8_t CdrReader::u8() { return *take(1, "uint8"); }
uint32_t CdrReader::u32() { return number<uint32_t>("uint32"); }
int32_t CdrReader::i32() { return number<int32_t>("int32"); }
double CdrReader::f64() { return number<double>("float64"); }

std::string CdrReader::string() {
  const uint32_t length = u32();
  if (length == 0) throw Error(where_, "CDR string of length 0 at byte " + num(pos_ + kEncapsulationBytes) + " (no terminator)");
  const uint8_t* p = take(length, "string");
  if (p[length - 1] != 0)
    throw Error(where_, "CDR string at byte " + num(pos_ - length + kEncapsulationBytes) + " has no NUL terminator");
  return std::string(reinterpret_cast<const char*>(p), length - 1);
}

std::span<const uint8_t> CdrReader::bytes() {
  const uint32_t count = u32();
  return {take(count, "byte sequence"), count};
}

std::vector<double> CdrReader::f64_sequence(size_t max_count) {
  const uint32_t count = u32();
  if (count > max_count) throw Error(where_, "CDR float64 sequence of " + num(count) + " elements (at most " + num(max_count) + " expected)");
  std::vector<double> out(count);
  for (double& v : out) v = f64();
  return out;
}

namespace ros2_msgs {

namespace {

constexpr size_t kMaxDistortionCoefficients = 64;

/// std_msgs/msg/Header: builtin_interfaces/Time (int32 sec, uint32 nanosec), string frame_id.
rb::Stamp header(CdrReader& in, const std::string& where) {
  const int32_t sec = in.i32();
  const uint32_t nanosec = in.u32();
  if (sec < 0) throw Error(where, "negative header stamp " + std::to_string(sec) + " s");
  in.string();  // frame_id
  return {static_cast<uint32_t>(sec), nanosec};
}

}  // namespace

rb::MessageType type_of(const std::string& t) {
  if (t == "sensor_msgs/msg/Image") return rb::MessageType::image;
  if (t == "sensor_msgs/msg/CompressedImage") return rb::MessageType::compressed_image;
  if (t == "sensor_msgs/msg/CameraInfo") return rb::MessageType::camera_info;
  return rb::MessageType::other;
}

rb::ImageMeta image_meta(std::span<const uint8_t> message, bool compressed, const std::string& where) {
  CdrReader in(message, where);
  rb::ImageMeta meta;
  meta.header_stamp = header(in, where);
  if (!compressed) {
    meta.height = in.u32();
    meta.width = in.u32();
  }
  meta.encoding = in.string();
  return meta;
}

// sensor_msgs/msg/Image: header, uint32 height, uint32 width, string encoding, uint8
// is_bigendian, uint32 step, uint8[] data.
rb::ImageData image(std::span<const uint8_t> message, const std::string& where) {
  CdrReader in(message, where);
  header(in, where);
  rb::ImageData out;
  out.height = in.u32();
  out.width = in.u32();
  out.encoding = in.string();
  out.big_endian = in.u8() != 0;
  out.step = in.u32();
  const auto data = in.bytes();
  out.data.assign(data.begin(), data.end());
  return out;
}

// sensor_msgs/msg/CompressedImage: header, string format, uint8[] data.
rb::CompressedData compressed_image(std::span<const uint8_t> message, const std::string& where) {
  CdrReader in(message, where);
  header(in, where);
  rb::CompressedData out;
  out.format = in.string();
  const auto data = in.bytes();
  out.data.assign(data.begin(), data.end());
  return out;
}

// sensor_msgs/msg/CameraInfo: header, uint32 height, uint32 width, string distortion_model,
// float64[] d, float64[9] k, (r, p, binning, roi: not read).
rb::CameraInfoData camera_info(std::span<const uint8_t> message, const std::string& where) {
  CdrReader in(message, where);
  rb::CameraInfoData out;
  out.header_stamp = header(in, where);
  out.height = in.u32();
  out.width = in.u32();
  out.distortion_model = in.string();
  out.D = in.f64_sequence(kMaxDistortionCoefficients);
  for (double& k : out.K) k = in.f64();
  return out;
}

}  // namespace ros2_msgs
}  // namespace semap::io_detail
