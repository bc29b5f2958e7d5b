#pragma once
// Test helper: writes ROS1 bags with the rosbag API (test_rosbag_writer.cpp is built as
// C++17, like src/io/rosbag_backend.cpp, because the ROS message headers are not C++20).
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace semap::test {

struct RosStamp {
  uint32_t sec = 0, nsec = 0;
};

struct RosImage {
  std::string topic;
  RosStamp stamp;
  std::string encoding;
  uint32_t width = 0, height = 0, step = 0;
  bool big_endian = false;
  std::vector<uint8_t> data;
};

struct RosCompressedImage {
  std::string topic;
  RosStamp stamp;
  std::string format;
  std::vector<uint8_t> data;
};

struct RosCameraInfo {
  std::string topic;
  RosStamp stamp;
  uint32_t width = 0, height = 0;
  std::array<double, 9> K{};
  std::vector<double> D;
  std::string distortion_model = "plumb_bob";
};

class BagWriter {
 public:
  /// lz4: compress the chunks (rosbag's LZ4 compression), else uncompressed.
  explicit BagWriter(const std::filesystem::path& path, bool lz4 = false);
  ~BagWriter();
  void write(const RosImage& image);
  void write(const RosCompressedImage& image);
  void write(const RosCameraInfo& info);
  /// A sensor_msgs/Imu message (a topic the reader must ignore).
  void write_imu(const std::string& topic, RosStamp stamp);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace semap::test
