#pragma once
// Internal to io/: ROS1 bag access through Debian's librosbag-storage (no ROS master, no
// catkin). The ROS message headers do not compile as C++20 (std::allocator<void>::rebind),
// so rosbag_backend.cpp is built as C++17 and this header stays free of ROS and of the
// project's C++20 headers: plain structs in, plain structs out.
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace semap::io_detail::rosbag_backend {

/// True when the library was built with ROS bag support (SEMAP_WITH_ROSBAG).
bool available();

enum class MessageType { image, compressed_image, camera_info, other };

struct Topic {
  std::string name;
  std::string datatype;  ///< "sensor_msgs/Image", ...
  MessageType type = MessageType::other;
  size_t messages = 0;
};

/// ROS time: seconds and nanoseconds.
struct Stamp {
  uint32_t sec = 0, nsec = 0;
  bool is_zero() const { return sec == 0 && nsec == 0; }
};

/// What is read of an image message without copying its pixels (Image: size and encoding;
/// CompressedImage: format in `encoding`).
struct ImageMeta {
  Stamp header_stamp, bag_stamp;
  uint32_t width = 0, height = 0;
  std::string encoding;
};

/// One indexed message: its topic (index into the topics asked for) and metadata.
struct IndexedMessage {
  size_t handle = 0;  ///< for read_image / read_compressed
  size_t topic = 0;
  ImageMeta meta;
};

struct ImageData {
  uint32_t width = 0, height = 0, step = 0;
  bool big_endian = false;
  std::string encoding;
  std::vector<uint8_t> data;
};
struct CompressedData {
  std::string format;
  std::vector<uint8_t> data;
};
struct CameraInfoData {
  Stamp header_stamp;
  uint32_t width = 0, height = 0;
  std::array<double, 9> K{};
  std::string distortion_model;
  std::vector<double> D;
};

/// A bag opened for reading. Thread-safe: reads are serialised inside (rosbag is not).
/// Every failure throws semap::Error naming the bag file.
class Bag {
 public:
  explicit Bag(const std::filesystem::path& path);
  ~Bag();
  Bag(const Bag&) = delete;
  Bag& operator=(const Bag&) = delete;

  const std::filesystem::path& path() const;
  std::vector<Topic> topics() const;
  /// Metadata of the first message on an image or compressed-image topic.
  ImageMeta first_image_meta(const std::string& topic) const;
  /// The first message on a compressed-image topic.
  CompressedData first_compressed(const std::string& topic) const;
  /// The first CameraInfo message on the topic.
  CameraInfoData first_camera_info(const std::string& topic) const;
  /// Every message of the given image topics in bag order, with its metadata; reads each
  /// message record once (the pixels are not deserialised).
  std::vector<IndexedMessage> index(const std::vector<std::string>& topics) const;
  ImageData read_image(size_t handle) const;
  CompressedData read_compressed(size_t handle) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace semap::io_detail::rosbag_backend
