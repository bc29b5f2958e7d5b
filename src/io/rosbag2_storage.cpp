// rosbag2 storages (rosbag2_storage.hpp). SQLite3: the schema of rosbag2_storage_sqlite3 in
// Humble (topics: id, name, type, serialization_format, offered_qos_profiles) and Jazzy (plus
// type_description_hash; tables schema and metadata): only the columns common to both are
// read: topics(id, name, type, serialization_format), messages(id, topic_id, timestamp, data).
#include "io/rosbag2_storage.hpp"

#include <spdlog/spdlog.h>
#include <sqlite3.h>

#include <algorithm>
#include <cstring>
#include <fstream>

#include "semap/core/error.hpp"
#include "io/mcap_reader.hpp"

namespace semap::io_detail::rosbag2 {

namespace fs = std::filesystem;

namespace {

std::string lower_extension(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

size_t topic_position(const std::vector<std::string>& topics, const std::string& name) {
  return static_cast<size_t>(std::find(topics.begin(), topics.end(), name) - topics.begin());
}

// ------------------------------------------------------------------ SQLite3

class Statement {
 public:
  Statement(sqlite3* db, const std::string& sql, const fs::path& file) : file_(file) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt_, nullptr) != SQLITE_OK)
      throw Error(file, std::string("not a rosbag2 SQLite database (") + sqlite3_errmsg(db) + ")");
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  sqlite3_stmt* get() const { return stmt_; }
  std::string text(int column) const {
    const auto* p = sqlite3_column_text(stmt_, column);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
  std::span<const uint8_t> blob(int column) const {
    const auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(stmt_, column));
    return {p, static_cast<size_t>(sqlite3_column_bytes(stmt_, column))};
  }

 private:
  sqlite3_stmt* stmt_ = nullptr;
  const fs::path& file_;
};

class SqliteStorage final : public Storage {
 public:
  explicit SqliteStorage(const fs::path& file) : path_(file) {
    char magic[16] = {};
    std::ifstream(file, std::ios::binary).read(magic, sizeof magic);
    if (std::memcmp(magic, "SQLite format 3", 16) != 0) throw Error(file, "not an SQLite3 database (no SQLite header)");
    if (sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
      const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      throw Error(file, "cannot open SQLite database: " + why);
    }
  }
  ~SqliteStorage() override { sqlite3_close(db_); }
  const fs::path& path() const override { return path_; }

  std::vector<StoredTopic> topics() override {
    std::vector<std::pair<int64_t, StoredTopic>> by_id;
    Statement topics(db_, "SELECT id, name, type, serialization_format FROM topics ORDER BY id", path_);
    while (step(topics)) by_id.push_back({sqlite3_column_int64(topics.get(), 0), {topics.text(1), topics.text(2), topics.text(3), 0}});
    Statement counts(db_, "SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id", path_);
    while (step(counts))
      for (auto& [id, t] : by_id)
        if (id == sqlite3_column_int64(counts.get(), 0)) t.messages = static_cast<size_t>(sqlite3_column_int64(counts.get(), 1));
    ids_.clear();
    std::vector<StoredTopic> out;
    for (auto& [id, t] : by_id) {
      ids_.push_back({id, t.name});
      out.push_back(std::move(t));
    }
    return out;
  }

  void visit(const std::vector<std::string>& names, const Visitor& visitor) override {
    if (ids_.empty()) topics();
    std::string in;
    for (const auto& [id, name] : ids_)
      if (topic_position(names, name) < names.size()) in += (in.empty() ? "" : ",") + std::to_string(id);
    if (in.empty()) return;
    Statement rows(db_, "SELECT id, topic_id, timestamp, data FROM messages WHERE topic_id IN (" + in + ") ORDER BY timestamp, id", path_);
    size_t seen = 0;
    for (;;) {
      try {
        if (!step(rows)) return;
      } catch (const Error&) {
        if (seen == 0) throw;
        // A database cut off while recording: the rows before the damage stand.
        spdlog::warn("{}: SQLite database damaged after {} messages (recording cut off?); reading those", path_.string(), seen);
        return;
      }
      ++seen;
      const int64_t topic_id = sqlite3_column_int64(rows.get(), 1);
      VisitedMessage m;
      for (const auto& [id, name] : ids_)
        if (id == topic_id) m.topic = topic_position(names, name);
      const int64_t stamp = sqlite3_column_int64(rows.get(), 2);
      m.log_time_ns = stamp > 0 ? static_cast<uint64_t>(stamp) : 0;
      m.data = rows.blob(3);
      m.ref = static_cast<uint64_t>(sqlite3_column_int64(rows.get(), 0));
      if (!visitor(m)) return;
    }
  }

  std::vector<uint8_t> read(uint64_t ref) override {
    Statement row(db_, "SELECT data FROM messages WHERE id = ?", path_);
    sqlite3_bind_int64(row.get(), 1, static_cast<int64_t>(ref));
    if (!step(row)) throw Error(path_, "message " + std::to_string(ref) + " is gone");
    const auto data = row.blob(0);
    return {data.begin(), data.end()};
  }

 private:
  bool step(const Statement& s) {
    const int rc = sqlite3_step(s.get());
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    throw Error(path_, std::string("SQLite: ") + sqlite3_errmsg(db_) + " (corrupt or truncated database?)");
  }

  fs::path path_;
  sqlite3* db_ = nullptr;
  std::vector<std::pair<int64_t, std::string>> ids_;  ///< topic id -> name
};

// ------------------------------------------------------------------ MCAP

class McapStorage final : public Storage {
 public:
  explicit McapStorage(const fs::path& file) : mcap_(file) {}
  const fs::path& path() const override { return mcap_.path(); }

  std::vector<StoredTopic> topics() override {
    std::vector<StoredTopic> out;
    for (const auto& c : mcap_.channels()) {
      size_t messages = 0;
      for (const auto& m : mcap_.messages()) messages += m.channel == c.id;
      out.push_back({c.topic, c.schema_name, c.message_encoding, messages});
    }
    return out;
  }

  void visit(const std::vector<std::string>& names, const Visitor& visitor) override {
    std::vector<size_t> position_of_channel(65536, names.size());
    for (const auto& c : mcap_.channels()) position_of_channel[c.id] = topic_position(names, c.topic);
    const auto& messages = mcap_.messages();
    for (size_t k = 0; k < messages.size(); ++k) {
      const size_t position = position_of_channel[messages[k].channel];
      if (position >= names.size()) continue;
      const std::vector<uint8_t> data = mcap_.read(messages[k]);
      if (!visitor({position, messages[k].log_time_ns, data, k})) return;
    }
  }

  std::vector<uint8_t> read(uint64_t ref) override {
    if (ref >= mcap_.messages().size()) throw Error(path(), "message reference out of range");
    return mcap_.read(mcap_.messages()[ref]);
  }

 private:
  McapReader mcap_;
};

}  // namespace

std::unique_ptr<Storage> open_storage(const fs::path& file) {
  const std::string ext = lower_extension(file);
  if (ext == ".db3") return std::make_unique<SqliteStorage>(file);
  if (ext == ".mcap") return std::make_unique<McapStorage>(file);
  throw Error(file, "not a rosbag2 storage file (.db3 or .mcap)");
}

}  // namespace semap::io_detail::rosbag2
