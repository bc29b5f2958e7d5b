#pragma once
// Internal to io/: a checked pre-pass over a ROS1 bag (format 2.0,
// http://wiki.ros.org/Bags/Format/2.0) run before Debian's librosbag opens it (issue 44).
// librosbag trusts every length and offset in the file: a record length or an index entry that
// points outside its chunk crashes it or makes it read past its buffer, and a chunk's declared
// size is allocated as is. This pass walks every top-level record and every record inside each
// chunk and checks, before librosbag sees the file:
//   - every header length, field length and data length against its record, chunk and the file;
//   - each chunk's declared uncompressed size against kMaxRos1ChunkBytes (and, when it is not
//     compressed, against its stored bytes); compressed chunks are decompressed once and must
//     give exactly their declared size;
//   - the bag header's index position, connection and chunk counts against the records there;
//   - every chunk-info position against a chunk record, every index entry's offset against the
//     start of a message record of that connection in its chunk, every connection id used
//     against a connection record.
// Memory is bounded by one chunk (kMaxRos1ChunkBytes) and the record headers.
#include <cstdint>
#include <filesystem>

namespace semap::io_detail {

/// Largest uncompressed ROS1 bag chunk accepted (rosbag writes 768 KiB chunks by default).
constexpr uint64_t kMaxRos1ChunkBytes = uint64_t{256} << 20;
/// Largest record header accepted (a few fields; connection headers carry a message definition).
constexpr uint64_t kMaxRos1HeaderBytes = uint64_t{1} << 20;

/// Throws semap::Error naming `bag` and the first problem found. Thread-safe (no shared state).
void validate_ros1_bag(const std::filesystem::path& bag);

}  // namespace semap::io_detail
