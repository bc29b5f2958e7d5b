// MCAP reading (mcap_reader.hpp). Record layouts from the MCAP specification, version 0:
// every record is opcode (uint8), content length (uint64), content; integers little endian;
// strings and maps carry a uint32 byte length, byte arrays a uint32 or uint64 one.
#include "io/mcap_reader.hpp"

#include <libdeflate.h>
#include <lz4frame.h>
#include <spdlog/spdlog.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <optional>
#include <span>

#include "semap/core/error.hpp"

namespace semap::io_detail {

namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
constexpr uint64_t kRecordHeaderBytes = 9;  // opcode + uint64 length
constexpr uint64_t kFooterContentBytes = 20;
constexpr uint64_t kMessageHeaderBytes = 2 + 4 + 8 + 8;

enum Opcode : uint8_t {
  kHeader = 0x01, kFooter = 0x02, kSchema = 0x03, kChannel = 0x04, kMessage = 0x05, kChunk = 0x06,
  kMessageIndex = 0x07, kChunkIndex = 0x08, kDataEnd = 0x0F,
};

std::string num(uint64_t v) { return std::to_string(v); }

/// Little-endian fields of one record's content; every read is bounded by the content.
class Fields {
 public:
  Fields(const uint8_t* data, uint64_t size, const std::filesystem::path& file, std::string record)
      : data_(data), size_(size), file_(file), record_(std::move(record)) {}
  template <class T>
  T number() {
    T v;
    std::memcpy(&v, take(sizeof v), sizeof v);  // MCAP is little endian, so is every target here
    return v;
  }
  std::string string() {
    const uint32_t n = number<uint32_t>();
    return std::string(reinterpret_cast<const char*>(take(n)), n);
  }
  void skip_u32_prefixed() { take(number<uint32_t>()); }
  /// A uint64-length byte array: its start and length.
  std::span<const uint8_t> u64_bytes() {
    const uint64_t n = number<uint64_t>();
    return {take(n), static_cast<size_t>(n)};
  }
  uint64_t position() const { return pos_; }
  uint64_t left() const { return size_ - pos_; }

 private:
  const uint8_t* take(uint64_t n) {
    if (n > size_ - pos_)
      throw Error(file_, record_ + ": a length field (" + num(n) + " bytes at byte " + num(pos_) +
                             ") runs past the end of its " + num(size_) + "-byte record");
    const uint8_t* p = data_ + pos_;
    pos_ += n;
    return p;
  }
  const uint8_t* data_;
  uint64_t size_, pos_ = 0;
  const std::filesystem::path& file_;
  std::string record_;
};

struct ChunkIndex {
  uint64_t chunk_offset = 0, chunk_length = 0;
};

std::vector<uint8_t> zstd_decompress(std::span<const uint8_t> in, uint64_t size, const std::filesystem::path& file,
                                     const std::string& where) {
  std::unique_ptr<ZSTD_DStream, decltype(&ZSTD_freeDStream)> stream(ZSTD_createDStream(), ZSTD_freeDStream);
  ZSTD_initDStream(stream.get());
  std::vector<uint8_t> out(std::min<uint64_t>(size, std::max<uint64_t>(4 * in.size(), 1 << 20)));
  ZSTD_inBuffer src{in.data(), in.size(), 0};
  ZSTD_outBuffer dst{out.data(), out.size(), 0};
  // Grows the output as data actually decompresses: memory follows the real content, not the
  // declared size.
  for (;;) {
    const size_t rc = ZSTD_decompressStream(stream.get(), &dst, &src);
    if (ZSTD_isError(rc)) throw Error(file, where + ": zstd: " + ZSTD_getErrorName(rc));
    if (rc == 0 && src.pos == src.size) break;
    if (dst.pos < dst.size) {
      if (src.pos == src.size) throw Error(file, where + ": zstd data ends early");
      continue;
    }
    if (out.size() >= size) throw Error(file, where + ": decompresses to more than the declared " + num(size) + " bytes");
    out.resize(std::min<uint64_t>(size, 2 * out.size()));
    dst = {out.data(), out.size(), dst.pos};
  }
  out.resize(dst.pos);
  return out;
}

std::vector<uint8_t> lz4_decompress(std::span<const uint8_t> in, uint64_t size, const std::filesystem::path& file,
                                    const std::string& where) {
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) throw Error(file, where + ": lz4 context");
  std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> ctx(raw, LZ4F_freeDecompressionContext);
  std::vector<uint8_t> out(std::min<uint64_t>(size, std::max<uint64_t>(4 * in.size(), 1 << 20)));
  size_t in_pos = 0, out_pos = 0;
  for (;;) {
    size_t in_n = in.size() - in_pos, out_n = out.size() - out_pos;
    const size_t rc = LZ4F_decompress(ctx.get(), out.data() + out_pos, &out_n, in.data() + in_pos, &in_n, nullptr);
    if (LZ4F_isError(rc)) throw Error(file, where + ": lz4: " + LZ4F_getErrorName(rc));
    in_pos += in_n;
    out_pos += out_n;
    if (rc == 0) break;  // frame complete
    if (in_pos == in.size() && out_pos < out.size()) throw Error(file, where + ": lz4 data ends early");
    if (out_pos == out.size()) {
      if (out.size() >= size) throw Error(file, where + ": decompresses to more than the declared " + num(size) + " bytes");
      out.resize(std::min<uint64_t>(size, 2 * out.size()));
    }
  }
  out.resize(out_pos);
  return out;
}

}  // namespace

McapReader::McapReader(const std::filesystem::path& file) : path_(file) {
  file_.open(file, std::ios::binary);
  if (!file_) throw Error(file, "cannot open");
  file_.seekg(0, std::ios::end);
  file_size_ = static_cast<uint64_t>(file_.tellg());
  const uint64_t head = std::min<uint64_t>(file_size_, 8 + kRecordHeaderBytes);
  const auto start = read_at(0, head);
  if (head < 8 || std::memcmp(start.data(), kMagic, 8) != 0) throw Error(file, "not an MCAP file (no MCAP magic at the start)");
  if (head < 8 + kRecordHeaderBytes) throw Error(file, "truncated MCAP file: ends before its header record");
  if (start[8] != kHeader) throw Error(file, "MCAP file does not start with a header record");
  if (!index_through_summary()) {
    reset();
    index_by_scan();
  }
}

void McapReader::reset() {
  channels_.clear();
  schemas_.clear();
  messages_.clear();
  chunks_.clear();
  cached_chunk_ = McapMessageRef::kNoChunk;
}

std::vector<uint8_t> McapReader::read_at(uint64_t offset, uint64_t size) {
  if (offset > file_size_ || size > file_size_ - offset)
    throw Error(path_, "read of " + num(size) + " bytes at byte " + num(offset) + " past the end of the " + num(file_size_) + "-byte file");
  std::vector<uint8_t> out(size);
  file_.clear();
  file_.seekg(static_cast<std::streamoff>(offset));
  file_.read(reinterpret_cast<char*>(out.data()), static_cast<std::streamsize>(size));
  if (static_cast<uint64_t>(file_.gcount()) != size) throw Error(path_, "read error at byte " + num(offset));
  return out;
}

/// The footer's summary: schemas, channels and chunk indexes. False (after a warning when the
/// summary is there but damaged) sends the caller to the linear scan.
bool McapReader::index_through_summary() {
  const uint64_t tail = kRecordHeaderBytes + kFooterContentBytes + 8;
  if (file_size_ < 8 + tail) return false;
  const auto end = read_at(file_size_ - tail, tail);
  if (std::memcmp(end.data() + tail - 8, kMagic, 8) != 0 || end[0] != kFooter) return false;  // cut off: no footer
  uint64_t length = 0, summary_start = 0;
  std::memcpy(&length, end.data() + 1, 8);
  std::memcpy(&summary_start, end.data() + 9, 8);
  if (summary_start == 0) return false;  // written without a summary
  const uint64_t footer_at = file_size_ - tail;
  const auto damaged = [&](const std::string& why) {
    spdlog::warn("{}: MCAP summary damaged ({}); scanning the data section instead", path_.string(), why);
    return false;
  };
  if (length != kFooterContentBytes || summary_start < 8 || summary_start >= footer_at) return damaged("footer points outside the file");
  if (footer_at - summary_start > kMaxMcapChunkBytes) return damaged("summary section larger than " + num(kMaxMcapChunkBytes) + " bytes");
  std::vector<ChunkIndex> indexes;
  try {
    const auto summary = read_at(summary_start, footer_at - summary_start);
    uint64_t pos = 0;
    while (pos < summary.size()) {
      if (summary.size() - pos < kRecordHeaderBytes) return damaged("record header cut at byte " + num(summary_start + pos));
      uint64_t n = 0;
      std::memcpy(&n, summary.data() + pos + 1, 8);
      if (n > summary.size() - pos - kRecordHeaderBytes) return damaged("record length past the summary's end");
      const uint8_t op = summary[pos];
      const uint8_t* content = summary.data() + pos + kRecordHeaderBytes;
      if (op == kSchema || op == kChannel) add_definition(op, content, n);
      if (op == kChunkIndex) {
        Fields f(content, n, path_, "chunk index at byte " + num(summary_start + pos));
        f.number<uint64_t>();  // message_start_time
        f.number<uint64_t>();  // message_end_time
        ChunkIndex index;
        index.chunk_offset = f.number<uint64_t>();
        index.chunk_length = f.number<uint64_t>();
        indexes.push_back(index);
      }
      pos += kRecordHeaderBytes + n;
    }
  } catch (const Error& e) {
    return damaged(e.what());
  }
  if (indexes.empty()) return false;  // messages outside chunks: only the scan finds them
  std::sort(indexes.begin(), indexes.end(), [](const auto& a, const auto& b) { return a.chunk_offset < b.chunk_offset; });
  for (const ChunkIndex& index : indexes) {
    if (index.chunk_offset < 8 || index.chunk_offset > summary_start || index.chunk_length > summary_start - index.chunk_offset ||
        index.chunk_length < kRecordHeaderBytes || index.chunk_length - kRecordHeaderBytes > kMaxMcapChunkBytes)
      return damaged("chunk index points outside the data section");
    const auto header = read_at(index.chunk_offset, kRecordHeaderBytes);
    uint64_t n = 0;
    std::memcpy(&n, header.data() + 1, 8);
    if (header[0] != kChunk || n != index.chunk_length - kRecordHeaderBytes)
      return damaged("chunk index at byte " + num(index.chunk_offset) + " does not point to a chunk");
  }
  // The index is sound: the chunks themselves are read like the scan reads them (their errors
  // are the file's, not the summary's).
  for (const ChunkIndex& index : indexes)
    add_chunk_record(index.chunk_offset, read_at(index.chunk_offset + kRecordHeaderBytes, index.chunk_length - kRecordHeaderBytes));
  through_summary_ = true;
  return true;
}

void McapReader::index_by_scan() {
  uint64_t pos = 8;
  while (pos < file_size_) {
    if (file_size_ - pos < kRecordHeaderBytes) break;
    const auto header = read_at(pos, kRecordHeaderBytes);
    uint64_t n = 0;
    std::memcpy(&n, header.data() + 1, 8);
    if (n > file_size_ - pos - kRecordHeaderBytes) break;
    const uint8_t op = header[0];
    if (op == kDataEnd || op == kFooter) return;
    if (op == kSchema || op == kChannel || op == kMessage || op == kChunk) {
      if (n > kMaxMcapChunkBytes)
        throw Error(path_, "record at byte " + num(pos) + " declares " + num(n) + " bytes (more than the " +
                               num(kMaxMcapChunkBytes) + "-byte limit)");
      const auto content = read_at(pos + kRecordHeaderBytes, n);
      if (op == kChunk) add_chunk_record(pos, content);
      else if (op != kMessage) add_definition(op, content.data(), n);
      if (op == kMessage) {
        if (n < kMessageHeaderBytes) throw Error(path_, "message record at byte " + num(pos) + " shorter than its header");
        McapMessageRef m;
        std::memcpy(&m.channel, content.data(), 2);
        std::memcpy(&m.log_time_ns, content.data() + 6, 8);
        m.offset = pos + kRecordHeaderBytes + kMessageHeaderBytes;
        m.size = n - kMessageHeaderBytes;
        messages_.push_back(m);
      }
    }
    pos += kRecordHeaderBytes + n;
  }
  // No data end record: the recording was cut off (or the file truncated later).
  if (messages_.empty())
    throw Error(path_, "truncated MCAP file: ends at byte " + num(pos) + " of its data section before any complete message");
  spdlog::warn("{}: MCAP file ends inside its data section at byte {} (recording cut off?); reading the {} complete "
               "messages before it",
               path_.string(), pos, messages_.size());
}

/// Schema and channel records (the rest of the definitions a reader may skip).
void McapReader::add_definition(uint8_t opcode, const uint8_t* data, uint64_t size) {
  if (opcode == kSchema) {
    Fields f(data, size, path_, "schema record");
    SchemaName s;
    s.id = f.number<uint16_t>();
    s.name = f.string();
    f.string();  // encoding ("ros2msg")
    f.skip_u32_prefixed();
    schemas_.push_back(std::move(s));
  } else if (opcode == kChannel) {
    Fields f(data, size, path_, "channel record");
    McapChannel c;
    c.id = f.number<uint16_t>();
    const uint16_t schema = f.number<uint16_t>();
    c.topic = f.string();
    c.message_encoding = f.string();
    for (const auto& s : schemas_)
      if (s.id == schema && schema != 0) c.schema_name = s.name;
    for (const auto& existing : channels_)
      if (existing.id == c.id) return;  // repeated in the summary or a later chunk
    channels_.push_back(std::move(c));
  }
}

/// A chunk record's content: registered, decompressed once, its messages indexed.
void McapReader::add_chunk_record(uint64_t record_offset, const std::vector<uint8_t>& content) {
  Fields f(content.data(), content.size(), path_, "chunk at byte " + num(record_offset));
  f.number<uint64_t>();  // message_start_time
  f.number<uint64_t>();  // message_end_time
  Chunk chunk;
  chunk.uncompressed_size = f.number<uint64_t>();
  chunk.crc = f.number<uint32_t>();
  chunk.compression = f.string();
  const auto records = f.u64_bytes();
  chunk.records_offset = record_offset + kRecordHeaderBytes + (records.data() - content.data());
  chunk.compressed_size = records.size();
  const auto data = decompress(chunk, record_offset, records);
  chunks_.push_back(chunk);
  add_records(data.data(), data.size(), chunks_.size() - 1, 0);
}

void McapReader::add_records(const uint8_t* data, uint64_t size, size_t chunk, uint64_t base_offset) {
  uint64_t pos = 0;
  while (pos < size) {
    const std::string where = "chunk " + num(chunk) + ", record at byte " + num(pos);
    if (size - pos < kRecordHeaderBytes) throw Error(path_, where + ": record header runs past the end of the chunk");
    uint64_t n = 0;
    std::memcpy(&n, data + pos + 1, 8);
    if (n > size - pos - kRecordHeaderBytes)
      throw Error(path_, where + ": length " + num(n) + " runs past the end of the chunk");
    const uint8_t op = data[pos];
    const uint8_t* content = data + pos + kRecordHeaderBytes;
    if (op == kSchema || op == kChannel) add_definition(op, content, n);
    if (op == kMessage) {
      if (n < kMessageHeaderBytes) throw Error(path_, where + ": message record shorter than its header");
      McapMessageRef m;
      std::memcpy(&m.channel, content, 2);
      std::memcpy(&m.log_time_ns, content + 6, 8);
      m.chunk = chunk;
      m.offset = base_offset + pos + kRecordHeaderBytes + kMessageHeaderBytes;
      m.size = n - kMessageHeaderBytes;
      messages_.push_back(m);
    }
    pos += kRecordHeaderBytes + n;
  }
}

std::vector<uint8_t> McapReader::decompress(const Chunk& chunk, uint64_t record_offset,
                                            std::span<const uint8_t> compressed) {
  const std::string where = "chunk at byte " + num(record_offset);
  if (chunk.compression != "" && chunk.compression != "lz4" && chunk.compression != "zstd")
    throw Error(path_, where + ": unknown compression '" + message_text(chunk.compression, 40) + "' (none, lz4, zstd)");
  if (chunk.uncompressed_size > kMaxMcapChunkBytes)
    throw Error(path_, where + " declares " + num(chunk.uncompressed_size) + " uncompressed bytes (more than the " +
                           num(kMaxMcapChunkBytes) + "-byte limit)");
  std::vector<uint8_t> out;
  if (chunk.compression.empty()) {
    if (chunk.compressed_size != chunk.uncompressed_size)
      throw Error(path_, where + ": uncompressed chunk of " + num(chunk.compressed_size) + " bytes declares " +
                             num(chunk.uncompressed_size));
    out.assign(compressed.begin(), compressed.end());
  } else {
    out = chunk.compression == "zstd" ? zstd_decompress(compressed, chunk.uncompressed_size, path_, where)
                                      : lz4_decompress(compressed, chunk.uncompressed_size, path_, where);
    if (out.size() != chunk.uncompressed_size)
      throw Error(path_, where + ": decompresses to " + num(out.size()) + " bytes, declared " + num(chunk.uncompressed_size));
  }
  if (chunk.crc != 0 && libdeflate_crc32(0, out.data(), out.size()) != chunk.crc)
    throw Error(path_, where + ": CRC mismatch (damaged file)");
  return out;
}

std::vector<uint8_t> McapReader::read(const McapMessageRef& m) {
  if (m.chunk == McapMessageRef::kNoChunk) return read_at(m.offset, m.size);
  if (m.chunk >= chunks_.size()) throw Error(path_, "message chunk out of range");
  if (cached_chunk_ != m.chunk) {
    cached_chunk_ = McapMessageRef::kNoChunk;
    const Chunk& chunk = chunks_[m.chunk];
    cached_records_ = decompress(chunk, chunk.records_offset, read_at(chunk.records_offset, chunk.compressed_size));
    cached_chunk_ = m.chunk;
  }
  if (m.offset > cached_records_.size() || m.size > cached_records_.size() - m.offset)
    throw Error(path_, "message outside its chunk");
  return {cached_records_.begin() + static_cast<ptrdiff_t>(m.offset), cached_records_.begin() + static_cast<ptrdiff_t>(m.offset + m.size)};
}

}  // namespace semap::io_detail
