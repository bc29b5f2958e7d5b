#pragma once
// Internal to io/: MCAP files (https://mcap.dev/spec, format version 0), the storage of
// rosbag2 since Iron. Opening indexes every message: through the summary section's chunk
// indexes when the footer points to a valid summary, else by a linear scan of the data section
// (no summary, or a damaged one: warned). Chunks are uncompressed, lz4 (frame format) or zstd.
// A file cut off while recording (no footer, a last record incomplete) gives every complete
// message before the cut, with one warning. Every length is bounded by its enclosing record
// and the file, a chunk's declared uncompressed size by kMaxChunkBytes before anything is
// allocated; a bad file is one semap::Error naming it.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <vector>

namespace semap::io_detail {

struct McapChannel {
  uint16_t id = 0;
  std::string topic, message_encoding;
  std::string schema_name;  ///< the ROS type ("sensor_msgs/msg/Image"); empty without a schema
};

/// Where one message's payload lies: in the data section (chunk == kNoChunk; offset in the
/// file) or inside chunk `chunk` (offset in its uncompressed records).
struct McapMessageRef {
  static constexpr size_t kNoChunk = SIZE_MAX;
  uint16_t channel = 0;
  uint64_t log_time_ns = 0;
  size_t chunk = kNoChunk;
  uint64_t offset = 0, size = 0;
};

/// Largest uncompressed chunk (or unchunked record) accepted.
constexpr uint64_t kMaxMcapChunkBytes = uint64_t{256} << 20;

/// Not thread-safe (one file handle and a one-chunk cache): callers serialise.
class McapReader {
 public:
  explicit McapReader(const std::filesystem::path& file);
  const std::filesystem::path& path() const { return path_; }
  const std::vector<McapChannel>& channels() const { return channels_; }
  /// Every message in file order (chunks in file order, messages in chunk order).
  const std::vector<McapMessageRef>& messages() const { return messages_; }
  std::vector<uint8_t> read(const McapMessageRef& message);
  bool read_through_summary() const { return through_summary_; }

 private:
  struct Chunk {
    uint64_t records_offset = 0, compressed_size = 0, uncompressed_size = 0;
    uint32_t crc = 0;
    std::string compression;
  };
  struct SchemaName {
    uint16_t id = 0;
    std::string name;
  };

  std::vector<uint8_t> read_at(uint64_t offset, uint64_t size);
  bool index_through_summary();
  void index_by_scan();
  void add_chunk_record(uint64_t record_offset, const std::vector<uint8_t>& content);
  void add_records(const uint8_t* data, uint64_t size, size_t chunk, uint64_t base_offset);
  void add_definition(uint8_t opcode, const uint8_t* data, uint64_t size);
  std::vector<uint8_t> decompress(const Chunk& chunk, uint64_t record_offset, std::span<const uint8_t> compressed);
  void reset();

  std::filesystem::path path_;
  std::ifstream file_;
  uint64_t file_size_ = 0;
  bool through_summary_ = false;
  std::vector<McapChannel> channels_;
  std::vector<SchemaName> schemas_;
  std::vector<McapMessageRef> messages_;
  std::vector<Chunk> chunks_;
  size_t cached_chunk_ = McapMessageRef::kNoChunk;
  std::vector<uint8_t> cached_records_;
};

}  // namespace semap::io_detail
