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
  std::string datatype;  ///< "sensor_msgs/Image" (ROS1), "sensor_msgs/msg/Image" (ROS 2), ...
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

/// Messages of a recording, whatever its storage: the ROS1 Bag below and the rosbag2 reader
/// (rosbag2_bag.hpp) both serve the dataset reader of rosbag_dataset.cpp through this.
/// Thread-safe: implementations serialise their reads inside. Every failure throws
/// semap::Error naming the file.
class BagSource {
 public:
  virtual ~BagSource() = default;
  virtual const std::filesystem::path& path() const = 0;
  virtual std::vector<Topic> topics() const = 0;
  /// Metadata of the first message on an image or compressed-image topic.
  virtual ImageMeta first_image_meta(const std::string& topic) const = 0;
  /// The first message on a compressed-image topic.
  virtual CompressedData first_compressed(const std::string& topic) const = 0;
  /// The first CameraInfo message on the topic.
  virtual CameraInfoData first_camera_info(const std::string& topic) const = 0;
  /// Every message of the given image topics in recording order, with its metadata; reads
  /// each message once (the pixels are not kept).
  virtual std::vector<IndexedMessage> index(const std::vector<std::string>& topics) const = 0;
  virtual ImageData read_image(size_t handle) const = 0;
  virtual CompressedData read_compressed(size_t handle) const = 0;
};

/// A ROS1 bag opened for reading (rosbag is not thread-safe: reads are serialised inside).
class Bag final : public BagSource {
 public:
  explicit Bag(const std::filesystem::path& path);
  ~Bag() override;
  Bag(const Bag&) = delete;
  Bag& operator=(const Bag&) = delete;

  const std::filesystem::path& path() const override;
  std::vector<Topic> topics() const override;
  ImageMeta first_image_meta(const std::string& topic) const override;
  CompressedData first_compressed(const std::string& topic) const override;
  CameraInfoData first_camera_info(const std::string& topic) const override;
  std::vector<IndexedMessage> index(const std::vector<std::string>& topics) const override;
  ImageData read_image(size_t handle) const override;
  CompressedData read_compressed(size_t handle) const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace semap::io_detail::rosbag_backend
