#pragma once
// Test helper (also seeds the fuzz targets): writes rosbag2 recordings as the ROS 2 tools do,
// with no ROS: CDR (XCDR1 little endian) messages, stored in SQLite3 .db3 files with the
// schema of Humble or Jazzy, or in MCAP files (chunked or not; chunks uncompressed, lz4 or
// zstd; with or without the summary section), split into several files with a metadata.yaml.
// The message structs are the ROS1 writer's (test_rosbag_writer.hpp, plain structs).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "test_rosbag_writer.hpp"

namespace semap::test {

/// CDR of sensor_msgs/msg/Image, CompressedImage, CameraInfo (full message) and Imu.
std::vector<uint8_t> cdr_image(const RosImage& m);
std::vector<uint8_t> cdr_compressed_image(const RosCompressedImage& m);
std::vector<uint8_t> cdr_camera_info(const RosCameraInfo& m);
std::vector<uint8_t> cdr_imu(RosStamp stamp);

enum class Rosbag2Storage { sqlite_humble, sqlite_jazzy, mcap };
enum class McapCompression { none, lz4, zstd };

struct Rosbag2WriterOptions {
  Rosbag2Storage storage = Rosbag2Storage::mcap;
  McapCompression compression = McapCompression::zstd;
  bool chunked = true;             ///< MCAP: messages in chunks (else in the data section)
  bool summary = true;             ///< MCAP: summary section (schemas, channels, statistics, chunk indexes)
  size_t chunk_bytes = 1 << 20;    ///< MCAP: a chunk is closed past this many uncompressed bytes
  size_t messages_per_file = 0;    ///< split the bag: a new storage file every N messages (0: one file)
};

/// Writes into `path`: a folder (created; <name>_N.<ext> files + metadata.yaml) or, when
/// `path` ends in .db3 / .mcap, that single file. Everything is written by close().
class Rosbag2Writer {
 public:
  Rosbag2Writer(std::filesystem::path path, Rosbag2WriterOptions options);
  ~Rosbag2Writer();
  void write(const RosImage& m);
  void write(const RosCompressedImage& m);
  void write(const RosCameraInfo& m);
  void write_imu(const std::string& topic, RosStamp stamp);
  /// Any message: topic, ROS 2 type, recording time and its serialised bytes.
  void write_raw(const std::string& topic, const std::string& type, uint64_t log_time_ns, std::vector<uint8_t> cdr);
  void close();

 private:
  struct Message {
    std::string topic, type;
    uint64_t log_time_ns = 0;
    std::vector<uint8_t> data;
  };
  void write_sqlite(const std::filesystem::path& file, const std::vector<Message>& messages) const;
  void write_mcap(const std::filesystem::path& file, const std::vector<Message>& messages) const;
  void write_metadata(const std::vector<std::string>& files) const;

  std::filesystem::path path_;
  Rosbag2WriterOptions options_;
  std::vector<Message> messages_;
  bool closed_ = false;
};

}  // namespace semap::test
