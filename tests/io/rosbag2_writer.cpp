// rosbag2 writer for the tests (rosbag2_writer.hpp). Layouts: CDR per the OMG CDR spec
// (XCDR1: encapsulation 00 01 00 00, primitives aligned to their size from after that
// header); SQLite per rosbag2_storage_sqlite3 (Humble / Jazzy); MCAP per its spec, version 0.
#include "rosbag2_writer.hpp"

#include <libdeflate.h>
#include <lz4frame.h>
#include <sqlite3.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <stdexcept>

namespace semap::test {

namespace fs = std::filesystem;

namespace {

class Cdr {
 public:
  Cdr() : out_{0x00, 0x01, 0x00, 0x00} {}
  template <class T>
  Cdr& number(T v) {
    while ((out_.size() - 4) % std::min(sizeof(T), size_t{8}) != 0) out_.push_back(0);
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    out_.insert(out_.end(), p, p + sizeof v);
    return *this;
  }
  Cdr& string(const std::string& s) {
    number<uint32_t>(static_cast<uint32_t>(s.size() + 1));
    out_.insert(out_.end(), s.begin(), s.end());
    out_.push_back(0);
    return *this;
  }
  Cdr& bytes(const std::vector<uint8_t>& b) {
    number<uint32_t>(static_cast<uint32_t>(b.size()));
    out_.insert(out_.end(), b.begin(), b.end());
    return *this;
  }
  Cdr& header(RosStamp stamp, const std::string& frame) {
    return number<int32_t>(static_cast<int32_t>(stamp.sec)).number<uint32_t>(stamp.nsec).string(frame);
  }
  std::vector<uint8_t> take() { return std::move(out_); }

 private:
  std::vector<uint8_t> out_;
};

uint64_t ns(RosStamp s) { return uint64_t{s.sec} * 1000000000u + s.nsec; }

// ------------------------------------------------------------------ MCAP

class Record {
 public:
  template <class T>
  Record& number(T v) {
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof v);
    return *this;
  }
  Record& string(const std::string& s) {
    number<uint32_t>(static_cast<uint32_t>(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    return *this;
  }
  Record& raw(const std::vector<uint8_t>& b) {
    bytes_.insert(bytes_.end(), b.begin(), b.end());
    return *this;
  }
  /// opcode, uint64 length, content appended to `out`.
  void append_to(uint8_t opcode, std::vector<uint8_t>& out) const {
    out.push_back(opcode);
    const uint64_t n = bytes_.size();
    const auto* p = reinterpret_cast<const uint8_t*>(&n);
    out.insert(out.end(), p, p + 8);
    out.insert(out.end(), bytes_.begin(), bytes_.end());
  }

 private:
  std::vector<uint8_t> bytes_;
};

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

std::vector<uint8_t> compress(const std::vector<uint8_t>& in, McapCompression c) {
  std::vector<uint8_t> out;
  if (c == McapCompression::zstd) {
    out.resize(ZSTD_compressBound(in.size()));
    out.resize(ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 1));
  } else {
    out.resize(LZ4F_compressFrameBound(in.size(), nullptr));
    out.resize(LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), nullptr));
  }
  return out;
}

struct ChunkInfo {
  uint64_t start = 0, end = 0, offset = 0, length = 0, index_length = 0, compressed = 0, uncompressed = 0;
  std::map<uint16_t, uint64_t> index_offsets;
};

}  // namespace

std::vector<uint8_t> cdr_image(const RosImage& m) {
  return Cdr().header(m.stamp, "camera").number<uint32_t>(m.height).number<uint32_t>(m.width).string(m.encoding)
      .number<uint8_t>(m.big_endian).number<uint32_t>(m.step).bytes(m.data).take();
}

std::vector<uint8_t> cdr_compressed_image(const RosCompressedImage& m) {
  return Cdr().header(m.stamp, "camera").string(m.format).bytes(m.data).take();
}

std::vector<uint8_t> cdr_camera_info(const RosCameraInfo& m) {
  Cdr c;
  c.header(m.stamp, "camera").number<uint32_t>(m.height).number<uint32_t>(m.width).string(m.distortion_model);
  c.number<uint32_t>(static_cast<uint32_t>(m.D.size()));
  for (double d : m.D) c.number<double>(d);
  for (double k : m.K) c.number<double>(k);
  for (double r : {1., 0., 0., 0., 1., 0., 0., 0., 1.}) c.number<double>(r);
  for (int i = 0; i < 12; ++i) c.number<double>(i % 4 < 3 ? m.K[i / 4 * 3 + i % 4] : 0.0);  // P = [K | 0]
  c.number<uint32_t>(0).number<uint32_t>(0);  // binning
  c.number<uint32_t>(0).number<uint32_t>(0).number<uint32_t>(0).number<uint32_t>(0).number<uint8_t>(0);  // roi
  return c.take();
}

std::vector<uint8_t> cdr_imu(RosStamp stamp) {
  Cdr c;
  c.header(stamp, "imu");
  for (int i = 0; i < 4; ++i) c.number<double>(i == 3 ? 1.0 : 0.0);  // orientation
  for (int block = 0; block < 3; ++block) {
    if (block > 0)
      for (int i = 0; i < 3; ++i) c.number<double>(0.1 * i);  // angular velocity, linear acceleration
    for (int i = 0; i < 9; ++i) c.number<double>(0.0);        // covariance
  }
  return c.take();
}

Rosbag2Writer::Rosbag2Writer(fs::path path, Rosbag2WriterOptions options) : path_(std::move(path)), options_(options) {}
Rosbag2Writer::~Rosbag2Writer() {
  if (!closed_) close();
}

void Rosbag2Writer::write_raw(const std::string& topic, const std::string& type, uint64_t t, std::vector<uint8_t> cdr) {
  messages_.push_back({topic, type, t, std::move(cdr)});
}
void Rosbag2Writer::write(const RosImage& m) { write_raw(m.topic, "sensor_msgs/msg/Image", ns(m.stamp), cdr_image(m)); }
void Rosbag2Writer::write(const RosCompressedImage& m) {
  write_raw(m.topic, "sensor_msgs/msg/CompressedImage", ns(m.stamp), cdr_compressed_image(m));
}
void Rosbag2Writer::write(const RosCameraInfo& m) {
  write_raw(m.topic, "sensor_msgs/msg/CameraInfo", ns(m.stamp), cdr_camera_info(m));
}
void Rosbag2Writer::write_imu(const std::string& topic, RosStamp stamp) {
  write_raw(topic, "sensor_msgs/msg/Imu", ns(stamp), cdr_imu(stamp));
}

void Rosbag2Writer::close() {
  closed_ = true;
  const std::string ext = options_.storage == Rosbag2Storage::mcap ? ".mcap" : ".db3";
  if (path_.extension() == ext) {
    options_.storage == Rosbag2Storage::mcap ? write_mcap(path_, messages_) : write_sqlite(path_, messages_);
    return;
  }
  fs::create_directories(path_);
  const size_t per_file = options_.messages_per_file ? options_.messages_per_file : messages_.size() + 1;
  std::vector<std::string> files;
  for (size_t begin = 0; begin < std::max<size_t>(messages_.size(), 1); begin += per_file) {
    const std::vector<Message> part(messages_.begin() + begin, messages_.begin() + std::min(messages_.size(), begin + per_file));
    files.push_back(path_.filename().string() + "_" + std::to_string(files.size()) + ext);
    options_.storage == Rosbag2Storage::mcap ? write_mcap(path_ / files.back(), part) : write_sqlite(path_ / files.back(), part);
  }
  write_metadata(files);
}

void Rosbag2Writer::write_sqlite(const fs::path& file, const std::vector<Message>& messages) const {
  fs::remove(file);
  sqlite3* db = nullptr;
  if (sqlite3_open(file.c_str(), &db) != SQLITE_OK) throw std::runtime_error("cannot create " + file.string());
  const bool jazzy = options_.storage == Rosbag2Storage::sqlite_jazzy;
  const auto exec = [&](const std::string& sql) {
    char* error = nullptr;
    if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) throw std::runtime_error(sql + ": " + error);
  };
  exec("PRAGMA journal_mode=MEMORY; BEGIN;");
  exec("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);");
  exec(std::string("INSERT INTO schema VALUES(") + (jazzy ? "4,'jazzy'" : "3,'humble'") + ");");
  if (jazzy) exec("CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,metadata TEXT NOT NULL);");
  exec(std::string("CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
                   "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL") +
       (jazzy ? ",type_description_hash TEXT NOT NULL" : "") + ");");
  exec("CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,timestamp INTEGER NOT NULL,data BLOB NOT NULL);");
  exec("CREATE INDEX timestamp_idx ON messages (timestamp ASC);");
  std::map<std::string, int> ids;
  sqlite3_stmt* insert = nullptr;
  sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?,?,?)", -1, &insert, nullptr);
  for (const Message& m : messages) {
    if (!ids.count(m.topic)) {
      ids[m.topic] = static_cast<int>(ids.size()) + 1;
      exec("INSERT INTO topics VALUES(" + std::to_string(ids[m.topic]) + ",'" + m.topic + "','" + m.type + "','cdr','- history: 3'" +
           (jazzy ? ",'RIHS01_0000'" : "") + ");");
    }
    sqlite3_bind_int(insert, 1, ids[m.topic]);
    sqlite3_bind_int64(insert, 2, static_cast<int64_t>(m.log_time_ns));
    sqlite3_bind_blob(insert, 3, m.data.data(), static_cast<int>(m.data.size()), SQLITE_STATIC);
    if (sqlite3_step(insert) != SQLITE_DONE) throw std::runtime_error("insert failed");
    sqlite3_reset(insert);
  }
  sqlite3_finalize(insert);
  exec("COMMIT;");
  sqlite3_close(db);
}

void Rosbag2Writer::write_mcap(const fs::path& file, const std::vector<Message>& messages) const {
  std::vector<uint8_t> out(kMagic, kMagic + 8);
  Record().string("ros2").string("semap-test").append_to(0x01, out);
  // Schemas and channels, numbered from 1 in order of first use.
  std::map<std::string, uint16_t> schema_ids, channel_ids;
  std::vector<std::vector<uint8_t>> definitions;  // schema and channel records, in order
  std::vector<std::vector<uint8_t>> definition_of_message(messages.size());
  std::map<uint16_t, uint64_t> counts;
  for (size_t i = 0; i < messages.size(); ++i) {
    const Message& m = messages[i];
    if (!schema_ids.count(m.type)) {
      const uint16_t id = static_cast<uint16_t>(schema_ids.size() + 1);
      schema_ids[m.type] = id;
      const std::string text = "# " + m.type + "\n";
      Record().number<uint16_t>(id).string(m.type).string("ros2msg").number<uint32_t>(uint32_t(text.size()))
          .raw({text.begin(), text.end()}).append_to(0x03, definition_of_message[i]);
    }
    if (!channel_ids.count(m.topic)) {
      const uint16_t id = static_cast<uint16_t>(channel_ids.size() + 1);
      channel_ids[m.topic] = id;
      const std::string k = "offered_qos_profiles", v = "- history: 3";
      Record().number<uint16_t>(id).number<uint16_t>(schema_ids[m.type]).string(m.topic).string("cdr")
          .number<uint32_t>(uint32_t(8 + k.size() + v.size())).string(k).string(v).append_to(0x04, definition_of_message[i]);
    }
    if (!definition_of_message[i].empty()) definitions.push_back(definition_of_message[i]);
    ++counts[channel_ids[m.topic]];
  }
  const auto message_record = [&](const Message& m, uint32_t sequence, std::vector<uint8_t>& to) {
    Record().number<uint16_t>(channel_ids.at(m.topic)).number<uint32_t>(sequence).number<uint64_t>(m.log_time_ns)
        .number<uint64_t>(m.log_time_ns).raw(m.data).append_to(0x05, to);
  };
  std::vector<ChunkInfo> chunks;
  if (!options_.chunked) {
    for (size_t i = 0; i < messages.size(); ++i) {
      out.insert(out.end(), definition_of_message[i].begin(), definition_of_message[i].end());
      message_record(messages[i], uint32_t(i), out);
    }
  } else {
    std::vector<uint8_t> records;
    std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> index;
    ChunkInfo info;
    const auto flush = [&] {
      if (records.empty()) return;
      const std::vector<uint8_t> stored = options_.compression == McapCompression::none ? records : compress(records, options_.compression);
      const std::string compression = options_.compression == McapCompression::none ? "" : options_.compression == McapCompression::lz4 ? "lz4" : "zstd";
      info.offset = out.size();
      info.compressed = stored.size();
      info.uncompressed = records.size();
      Record().number<uint64_t>(info.start).number<uint64_t>(info.end).number<uint64_t>(records.size())
          .number<uint32_t>(libdeflate_crc32(0, records.data(), records.size())).string(compression)
          .number<uint64_t>(stored.size()).raw(stored).append_to(0x06, out);
      info.length = out.size() - info.offset;
      const uint64_t index_start = out.size();
      for (const auto& [channel, entries] : index) {
        info.index_offsets[channel] = out.size();
        Record r;
        r.number<uint16_t>(channel).number<uint32_t>(uint32_t(entries.size() * 16));
        for (const auto& [t, offset] : entries) r.number<uint64_t>(t).number<uint64_t>(offset);
        r.append_to(0x07, out);
      }
      info.index_length = out.size() - index_start;
      chunks.push_back(info);
      records.clear();
      index.clear();
      info = ChunkInfo{};
    };
    for (size_t i = 0; i < messages.size(); ++i) {
      if (records.empty()) info.start = messages[i].log_time_ns;
      records.insert(records.end(), definition_of_message[i].begin(), definition_of_message[i].end());
      index[channel_ids[messages[i].topic]].push_back({messages[i].log_time_ns, records.size()});
      message_record(messages[i], uint32_t(i), records);
      info.start = std::min(info.start, messages[i].log_time_ns);
      info.end = std::max(info.end, messages[i].log_time_ns);
      if (records.size() >= options_.chunk_bytes) flush();
    }
    flush();
  }
  Record().number<uint32_t>(0).append_to(0x0F, out);  // data end, no CRC
  uint64_t summary_start = 0, summary_offset_start = 0;
  if (options_.summary) {
    summary_start = out.size();
    std::vector<std::tuple<uint8_t, uint64_t, uint64_t>> groups;
    uint64_t group = out.size();
    for (const auto& d : definitions)
      if (d[0] == 0x03) out.insert(out.end(), d.begin(), d.end());
    groups.emplace_back(0x03, group, out.size() - group);
    group = out.size();
    for (const auto& d : definitions)
      if (d[0] == 0x04) out.insert(out.end(), d.begin(), d.end());
    groups.emplace_back(0x04, group, out.size() - group);
    group = out.size();
    Record stats;
    stats.number<uint64_t>(messages.size()).number<uint16_t>(uint16_t(schema_ids.size())).number<uint32_t>(uint32_t(channel_ids.size()))
        .number<uint32_t>(0).number<uint32_t>(0).number<uint32_t>(uint32_t(chunks.size()))
        .number<uint64_t>(messages.empty() ? 0 : messages.front().log_time_ns).number<uint64_t>(messages.empty() ? 0 : messages.back().log_time_ns)
        .number<uint32_t>(uint32_t(counts.size() * 10));
    for (const auto& [channel, n] : counts) stats.number<uint16_t>(channel).number<uint64_t>(n);
    stats.append_to(0x0B, out);
    groups.emplace_back(0x0B, group, out.size() - group);
    if (!chunks.empty()) {
      group = out.size();
      for (const ChunkInfo& c : chunks) {
        Record r;
        r.number<uint64_t>(c.start).number<uint64_t>(c.end).number<uint64_t>(c.offset).number<uint64_t>(c.length)
            .number<uint32_t>(uint32_t(c.index_offsets.size() * 10));
        for (const auto& [channel, offset] : c.index_offsets) r.number<uint16_t>(channel).number<uint64_t>(offset);
        const std::string compression = options_.compression == McapCompression::none ? "" : options_.compression == McapCompression::lz4 ? "lz4" : "zstd";
        r.number<uint64_t>(c.index_length).string(compression).number<uint64_t>(c.compressed).number<uint64_t>(c.uncompressed);
        r.append_to(0x08, out);
      }
      groups.emplace_back(0x08, group, out.size() - group);
    }
    summary_offset_start = out.size();
    for (const auto& [op, start, length] : groups)
      Record().number<uint8_t>(op).number<uint64_t>(start).number<uint64_t>(length).append_to(0x0E, out);
  }
  Record().number<uint64_t>(summary_start).number<uint64_t>(summary_offset_start).number<uint32_t>(0).append_to(0x02, out);
  out.insert(out.end(), kMagic, kMagic + 8);
  std::ofstream(file, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
}

void Rosbag2Writer::write_metadata(const std::vector<std::string>& files) const {
  const bool mcap = options_.storage == Rosbag2Storage::mcap;
  std::map<std::string, std::pair<std::string, size_t>> topics;
  for (const Message& m : messages_) {
    topics[m.topic].first = m.type;
    ++topics[m.topic].second;
  }
  std::ofstream y(path_ / "metadata.yaml");
  y << "rosbag2_bagfile_information:\n  version: " << (options_.storage == Rosbag2Storage::sqlite_humble ? 5 : 9)
    << "\n  storage_identifier: " << (mcap ? "mcap" : "sqlite3") << "\n  duration:\n    nanoseconds: "
    << (messages_.empty() ? 0 : messages_.back().log_time_ns - messages_.front().log_time_ns)
    << "\n  starting_time:\n    nanoseconds_since_epoch: " << (messages_.empty() ? 0 : messages_.front().log_time_ns)
    << "\n  message_count: " << messages_.size() << "\n  topics_with_message_count:\n";
  for (const auto& [name, t] : topics)
    y << "    - topic_metadata:\n        name: " << name << "\n        type: " << t.first
      << "\n        serialization_format: cdr\n        offered_qos_profiles: \"\"\n      message_count: " << t.second << "\n";
  y << "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n";
  for (const auto& f : files) y << "    - " << f << "\n";
  y << "  files:\n";
  for (const auto& f : files) y << "    - path: " << f << "\n";
}

}  // namespace semap::test
