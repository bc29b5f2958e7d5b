// Checked pre-pass over a ROS1 bag before librosbag reads it (rosbag_validate.hpp, issue 44).
#include "io/rosbag_validate.hpp"

#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "semap/core/error.hpp"

#ifdef SEMAP_WITH_ROSBAG
#include <bzlib.h>
#include <roslz4/lz4s.h>
#endif

namespace semap::io_detail {

namespace {

enum Op : uint8_t { kMessage = 0x02, kBagHeader = 0x03, kIndex = 0x04, kChunk = 0x05, kChunkInfo = 0x06, kConnection = 0x07 };

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr uint64_t kMagicBytes = sizeof(kMagic) - 1;

using Fields = std::map<std::string, std::string>;

/// One record: its header fields and where its data lies (in the file or in a chunk buffer).
struct Record {
  uint64_t offset = 0, data_offset = 0, data_bytes = 0;
  uint8_t op = 0;
  Fields fields;
};

/// Record parsing shared by the file and the chunk buffers; every failure names the bag and
/// where in it (`where`: "at byte N" / "in the chunk at byte N, at offset M").
class Checker {
 public:
  explicit Checker(const std::filesystem::path& bag) : bag_(bag) {}

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw Error(bag_, "corrupt ROS bag: " + what + " " + where);
  }

  static uint32_t u32(const uint8_t* p) {
    uint32_t v = 0;
    std::memcpy(&v, p, 4);  // little-endian (the bag format's byte order, and the host's)
    return v;
  }
  static uint64_t u64(const uint8_t* p) {
    uint64_t v = 0;
    std::memcpy(&v, p, 8);
    return v;
  }

  /// Header fields "len name=value" packed over `bytes`.
  Fields parse_fields(const uint8_t* bytes, uint64_t size, const std::string& where) const {
    Fields fields;
    uint64_t pos = 0;
    while (pos < size) {
      if (size - pos < 4) fail(where, "header field length cut off");
      const uint64_t len = u32(bytes + pos);
      pos += 4;
      if (len > size - pos) fail(where, "header field of " + std::to_string(len) + " bytes overruns its header");
      const std::string field(reinterpret_cast<const char*>(bytes + pos), len);
      pos += len;
      const size_t eq = field.find('=');
      if (eq == std::string::npos) fail(where, "header field without '='");
      fields[field.substr(0, eq)] = field.substr(eq + 1);
    }
    return fields;
  }

  /// A field of exactly `bytes` bytes (4 or 8), as a number.
  uint64_t number(const Record& r, const std::string& name, size_t bytes, const std::string& where) const {
    const auto it = r.fields.find(name);
    if (it == r.fields.end()) fail(where, "record without its '" + name + "' field");
    if (it->second.size() != bytes) fail(where, "field '" + name + "' is not " + std::to_string(bytes) + " bytes");
    const auto* p = reinterpret_cast<const uint8_t*>(it->second.data());
    return bytes == 4 ? u32(p) : u64(p);
  }

  std::string text(const Record& r, const std::string& name, const std::string& where) const {
    const auto it = r.fields.find(name);
    if (it == r.fields.end()) fail(where, "record without its '" + name + "' field");
    return it->second;
  }

  uint8_t op_of(const Record& r, const std::string& where) const {
    const auto it = r.fields.find("op");
    if (it == r.fields.end() || it->second.size() != 1) fail(where, "record without a one-byte 'op' field");
    return static_cast<uint8_t>(it->second[0]);
  }

  /// Reads the record at `offset` of an in-memory buffer of `size` bytes.
  Record record_in(const uint8_t* buf, uint64_t size, uint64_t offset, const std::string& where) const {
    Record r;
    r.offset = offset;
    if (size - offset < 4) fail(where, "record header length cut off");
    const uint64_t header_bytes = u32(buf + offset);
    if (header_bytes > kMaxRos1HeaderBytes || header_bytes + 4 > size - offset - 4)
      fail(where, "record header of " + std::to_string(header_bytes) + " bytes overruns its chunk");
    r.fields = parse_fields(buf + offset + 4, header_bytes, where);
    r.op = op_of(r, where);
    r.data_bytes = u32(buf + offset + 4 + header_bytes);
    r.data_offset = offset + 8 + header_bytes;
    if (r.data_bytes > size - r.data_offset) fail(where, "record data of " + std::to_string(r.data_bytes) + " bytes overruns its chunk");
    return r;
  }

 private:
  std::filesystem::path bag_;
};

std::string at(uint64_t offset) { return "at byte " + std::to_string(offset); }

/// Message records of one chunk: offset in the uncompressed chunk -> connection id.
struct ChunkSummary {
  std::map<uint64_t, uint32_t> messages;
  size_t index_records = 0;
};

class BagWalk {
 public:
  explicit BagWalk(const std::filesystem::path& bag) : bag_(bag), check_(bag), in_(bag, std::ios::binary) {
    std::error_code ec;
    file_bytes_ = std::filesystem::file_size(bag, ec);
    if (!in_ || ec) throw Error(bag, "cannot read the bag");
  }

  void run() {
    std::string magic(kMagicBytes, '\0');
    if (file_bytes_ < kMagicBytes || !in_.read(magic.data(), kMagicBytes) || magic != kMagic)
      throw Error(bag_, "not a ROS bag of format 2.0 (no '#ROSBAG V2.0' line)");
    uint64_t offset = kMagicBytes;
    while (offset < file_bytes_) offset = top_level(offset);
    check_index_section();
  }

 private:
  std::vector<uint8_t> read_at(uint64_t offset, uint64_t bytes) {
    std::vector<uint8_t> out(bytes);
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(offset));
    if (!in_.read(reinterpret_cast<char*>(out.data()), static_cast<std::streamsize>(bytes))) check_.fail(at(offset), "read failed");
    return out;
  }

  /// Reads the top-level record at `offset` (lengths bounded by the file); returns the next offset.
  uint64_t top_level(uint64_t offset) {
    const std::string where = at(offset);
    if (file_bytes_ - offset < 8) check_.fail(where, "record cut off (truncated bag?)");
    const uint64_t header_bytes = Checker::u32(read_at(offset, 4).data());
    if (header_bytes > kMaxRos1HeaderBytes || header_bytes > file_bytes_ - offset - 8)
      check_.fail(where, "record header of " + std::to_string(header_bytes) + " bytes overruns the file");
    const auto head = read_at(offset + 4, header_bytes + 4);
    Record r;
    r.offset = offset;
    r.fields = check_.parse_fields(head.data(), header_bytes, where);
    r.op = check_.op_of(r, where);
    r.data_bytes = Checker::u32(head.data() + header_bytes);
    r.data_offset = offset + 8 + header_bytes;
    if (r.data_bytes > file_bytes_ - r.data_offset)
      check_.fail(where, "record data of " + std::to_string(r.data_bytes) + " bytes overruns the file (truncated bag?)");
    visit(r, where);
    ops_.emplace_back(offset, r.op);
    return r.data_offset + r.data_bytes;
  }

  void visit(const Record& r, const std::string& where) {
    if (r.op != kBagHeader && ops_.empty()) check_.fail(where, "first record is not the bag header");
    switch (r.op) {
      case kBagHeader:
        if (!ops_.empty()) check_.fail(where, "second bag header");
        index_pos_ = check_.number(r, "index_pos", 8, where);
        connection_count_ = check_.number(r, "conn_count", 4, where);
        chunk_count_ = check_.number(r, "chunk_count", 4, where);
        return;
      case kConnection:
        connection(r, read_at(r.data_offset, r.data_bytes).data(), where);
        return;
      case kChunk:
        chunk(r, where);
        return;
      case kIndex:
        index(r, where);
        return;
      case kChunkInfo:
        chunk_info(r, where);
        return;
      default:
        check_.fail(where, "unexpected record (op " + std::to_string(r.op) + ") at the top level");
    }
  }

  void connection(const Record& r, const uint8_t* data, const std::string& where) {
    if (r.data_bytes > kMaxRos1HeaderBytes) check_.fail(where, "connection header over the byte limit");
    connections_.insert(static_cast<uint32_t>(check_.number(r, "conn", 4, where)));
    check_.text(r, "topic", where);
    check_.parse_fields(data, r.data_bytes, where);  // the connection header (type, md5sum, ...)
  }

  std::vector<uint8_t> chunk_bytes(const Record& r, const std::string& where) {
    const std::string compression = check_.text(r, "compression", where);
    const uint64_t size = check_.number(r, "size", 4, where);
    if (size > kMaxRos1ChunkBytes)
      check_.fail(where, "chunk of " + std::to_string(size) + " bytes (over the " + std::to_string(kMaxRos1ChunkBytes) + "-byte limit)");
    if (compression == "none") {
      if (size != r.data_bytes) check_.fail(where, "uncompressed chunk whose size field differs from its data length");
      return read_at(r.data_offset, r.data_bytes);
    }
    if (r.data_bytes > kMaxRos1ChunkBytes) check_.fail(where, "compressed chunk over the byte limit");
    auto packed = read_at(r.data_offset, r.data_bytes);
    std::vector<uint8_t> out(size);
    unsigned int out_bytes = static_cast<unsigned int>(size);
    bool ok = false;
#ifdef SEMAP_WITH_ROSBAG
    if (compression == "bz2")
      ok = BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(out.data()), &out_bytes, reinterpret_cast<char*>(packed.data()),
                                      static_cast<unsigned int>(packed.size()), 0, 0) == BZ_OK;
    else if (compression == "lz4")
      ok = roslz4_buffToBuffDecompress(reinterpret_cast<char*>(packed.data()), static_cast<unsigned int>(packed.size()),
                                       reinterpret_cast<char*>(out.data()), &out_bytes) == ROSLZ4_OK;
    else
      check_.fail(where, "unknown chunk compression '" + message_text(compression, 40) + "'");
#else
    check_.fail(where, "compressed chunk ('" + message_text(compression, 40) + "'): built without ROS bag support");
#endif
    if (!ok || out_bytes != size) check_.fail(where, "chunk does not decompress to its declared " + std::to_string(size) + " bytes");
    return out;
  }

  void chunk(const Record& r, const std::string& where) {
    const auto bytes = chunk_bytes(r, where);
    ChunkSummary summary;
    for (uint64_t pos = 0; pos < bytes.size();) {
      const std::string inner = "in the chunk " + where + ", at offset " + std::to_string(pos);
      const Record m = check_.record_in(bytes.data(), bytes.size(), pos, inner);
      if (m.op == kConnection) {
        connection(m, bytes.data() + m.data_offset, inner);
      } else if (m.op == kMessage) {
        check_.number(m, "time", 8, inner);
        summary.messages[pos] = static_cast<uint32_t>(check_.number(m, "conn", 4, inner));
      } else {
        check_.fail(inner, "unexpected record (op " + std::to_string(m.op) + ") inside a chunk");
      }
      pos = m.data_offset + m.data_bytes;
    }
    for (const auto& [pos, conn] : summary.messages) used_connections_.insert(conn);  // checked at the end
    chunks_[r.offset] = std::move(summary);
    last_chunk_ = r.offset;
  }

  void index(const Record& r, const std::string& where) {
    if (!last_chunk_) check_.fail(where, "index record before any chunk");
    if (check_.number(r, "ver", 4, where) != 1) check_.fail(where, "index record of an unknown version");
    const uint32_t conn = static_cast<uint32_t>(check_.number(r, "conn", 4, where));
    const uint64_t count = check_.number(r, "count", 4, where);
    if (count * 12 != r.data_bytes) check_.fail(where, "index record whose count does not match its data length");
    ChunkSummary& chunk = chunks_[*last_chunk_];
    ++chunk.index_records;
    const auto data = read_at(r.data_offset, r.data_bytes);
    for (uint64_t k = 0; k < count; ++k) {
      const uint64_t offset = Checker::u32(data.data() + 12 * k + 8);
      const auto it = chunk.messages.find(offset);
      if (it == chunk.messages.end() || it->second != conn)
        check_.fail(where, "index entry points to offset " + std::to_string(offset) + ", not to a message of connection " +
                               std::to_string(conn) + " in its chunk");
    }
  }

  void chunk_info(const Record& r, const std::string& where) {
    if (check_.number(r, "ver", 4, where) != 1) check_.fail(where, "chunk info of an unknown version");
    const uint64_t chunk_pos = check_.number(r, "chunk_pos", 8, where);
    check_.number(r, "start_time", 8, where);
    check_.number(r, "end_time", 8, where);
    const uint64_t count = check_.number(r, "count", 4, where);
    if (count * 8 != r.data_bytes) check_.fail(where, "chunk info whose count does not match its data length");
    const auto it = chunks_.find(chunk_pos);
    if (it == chunks_.end()) check_.fail(where, "chunk info points to byte " + std::to_string(chunk_pos) + ", not to a chunk");
    // librosbag reads one index record after the chunk per connection listed here.
    if (count > it->second.index_records) check_.fail(where, "chunk info lists more connections than its chunk has index records");
    const auto data = read_at(r.data_offset, r.data_bytes);
    for (uint64_t k = 0; k < count; ++k) used_connections_.insert(Checker::u32(data.data() + 8 * k));
  }

  /// librosbag seeks to index_pos and reads conn_count connections, then chunk_count chunk infos.
  void check_index_section() {
    for (const uint32_t conn : used_connections_)
      if (!connections_.count(conn)) throw Error(bag_, "corrupt ROS bag: messages of connection " + std::to_string(conn) + ", which no connection record defines");
    if (index_pos_ == 0) throw Error(bag_, "the bag is not indexed (recording cut off?): run `rosbag reindex` on it");
    size_t k = 0;
    while (k < ops_.size() && ops_[k].first != index_pos_) ++k;
    if (k == ops_.size()) throw Error(bag_, "corrupt ROS bag: the bag header's index position " + std::to_string(index_pos_) + " is not a record");
    for (uint64_t n = 0; n < connection_count_ + chunk_count_; ++n, ++k) {
      const uint8_t want = n < connection_count_ ? kConnection : kChunkInfo;
      if (k >= ops_.size() || ops_[k].second != want)
        throw Error(bag_, "corrupt ROS bag: the index section does not hold the " + std::to_string(connection_count_) +
                              " connections and " + std::to_string(chunk_count_) + " chunk infos its header declares");
    }
  }

  std::filesystem::path bag_;
  Checker check_;
  std::ifstream in_;
  uint64_t file_bytes_ = 0;
  uint64_t index_pos_ = 0, connection_count_ = 0, chunk_count_ = 0;
  std::vector<std::pair<uint64_t, uint8_t>> ops_;  ///< top-level records: offset, op
  std::set<uint32_t> connections_, used_connections_;  ///< defined by connection records; used by messages
  std::map<uint64_t, ChunkSummary> chunks_;  ///< by the chunk record's offset
  std::optional<uint64_t> last_chunk_;
};

}  // namespace

void validate_ros1_bag(const std::filesystem::path& bag) { BagWalk(bag).run(); }

}  // namespace semap::io_detail
