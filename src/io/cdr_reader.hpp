#pragma once
// Internal to io/: CDR (OMG CDR / XCDR1, the serialisation of ROS 2 messages in rosbag2) and
// the few sensor_msgs/msg types semap reads. A serialised message starts with a 4-byte
// encapsulation header (representation id 00 01 = CDR little endian, 00 00 = big endian,
// then 2 option bytes); each primitive is aligned to its size (at most 8) counted from the
// byte after that header. Every length is checked against the message: a bad message is one
// semap::Error naming `where` (the storage file) and the problem.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "io/rosbag_backend.hpp"

namespace semap::io_detail {

class CdrReader {
 public:
  /// Checks the encapsulation header; `where` names the file (and topic) in errors.
  CdrReader(std::span<const uint8_t> message, std::string where);
  uint8_t u8();
  uint32_t u32();
  int32_t i32();
  double f64();
  /// string: uint32 length counting the terminating NUL, the bytes, the NUL.
  std::string string();
  /// sequence<uint8>: uint32 count, the bytes (a view into the message).
  std::span<const uint8_t> bytes();
  /// sequence<float64> of at most max_count elements.
  std::vector<double> f64_sequence(size_t max_count);
  size_t offset() const { return pos_; }

 private:
  void align(size_t n);
  const uint8_t* take(size_t n, const char* what);
  template <class T>
  T number(const char* what);

  std::span<const uint8_t> body_;  ///< after the encapsulation header
  size_t pos_ = 0;
  bool big_endian_ = false;
  std::string where_;
};

namespace ros2_msgs {
namespace rb = rosbag_backend;
/// std_msgs/msg/Header and the image metadata of sensor_msgs/msg/Image (compressed=false) or
/// CompressedImage (compressed=true; its format goes to `encoding`), pixels not copied.
rb::ImageMeta image_meta(std::span<const uint8_t> message, bool compressed, const std::string& where);
rb::ImageData image(std::span<const uint8_t> message, const std::string& where);
rb::CompressedData compressed_image(std::span<const uint8_t> message, const std::string& where);
rb::CameraInfoData camera_info(std::span<const uint8_t> message, const std::string& where);
/// The ROS 2 type names of the three types ("sensor_msgs/msg/Image", ...); other types: other.
rb::MessageType type_of(const std::string& ros2_type);
}  // namespace ros2_msgs

}  // namespace semap::io_detail
