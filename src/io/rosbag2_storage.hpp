#pragma once
// Internal to io/: the two rosbag2 storages behind one interface (rosbag2_storage.cpp:
// SQLite3 .db3; MCAP .mcap through mcap_reader.hpp). Not thread-safe: the rosbag2 source
// (rosbag2_bag.cpp) serialises every call.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace semap::io_detail::rosbag2 {

struct StoredTopic {
  std::string name, type, serialization_format;  ///< e.g. /camera/rgb, sensor_msgs/msg/Image, cdr
  size_t messages = 0;
};

/// One message met by Storage::visit: which of the asked topics, its recording time, payload
/// (valid during the call) and a reference for Storage::read.
struct VisitedMessage {
  size_t topic = 0;
  uint64_t log_time_ns = 0;
  std::span<const uint8_t> data;
  uint64_t ref = 0;
};
/// Returns false to stop the visit.
using Visitor = std::function<bool(const VisitedMessage&)>;

class Storage {
 public:
  virtual ~Storage() = default;
  virtual const std::filesystem::path& path() const = 0;
  virtual std::vector<StoredTopic> topics() = 0;
  /// Every message of the named topics, in recording order.
  virtual void visit(const std::vector<std::string>& topics, const Visitor& visitor) = 0;
  virtual std::vector<uint8_t> read(uint64_t ref) = 0;
};

/// By extension: .db3 (SQLite3) or .mcap; anything else is an error naming the file.
std::unique_ptr<Storage> open_storage(const std::filesystem::path& file);

}  // namespace semap::io_detail::rosbag2
