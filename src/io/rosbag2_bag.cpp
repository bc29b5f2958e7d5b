// rosbag2 recordings as a BagSource (rosbag2_bag.hpp): metadata.yaml, the storage files in
// order, CDR messages decoded by cdr_reader.cpp.
#include "io/rosbag2_bag.hpp"

#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>

#include "semap/core/error.hpp"
#include "io/cdr_reader.hpp"
#include "io/rosbag2_storage.hpp"

namespace semap::io_detail {

namespace fs = std::filesystem;
namespace rb = rosbag_backend;

namespace {

bool is_storage_file(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".db3" || ext == ".mcap";
}

/// "bag_10.db3" after "bag_9.db3": the trailing number of the stem compares as a number.
bool natural_less(const fs::path& a, const fs::path& b) {
  const auto split = [](const fs::path& p) {
    const std::string stem = p.stem().string();
    size_t digits = stem.size();
    while (digits > 0 && std::isdigit(static_cast<unsigned char>(stem[digits - 1]))) --digits;
    const std::string number = stem.substr(digits);
    return std::make_tuple(stem.substr(0, digits), number.size(), number, p.extension().string());
  };
  return split(a) < split(b);
}

std::vector<fs::path> listed_files(const fs::path& metadata) {
  const fs::path folder = metadata.parent_path();
  YAML::Node info;
  try {
    info = YAML::LoadFile(metadata.string())["rosbag2_bagfile_information"];
  } catch (const YAML::Exception& e) {
    throw Error(metadata, "not valid YAML: " + e.msg);
  }
  if (!info || !info.IsMap()) throw Error(metadata, "no rosbag2_bagfile_information map (not a rosbag2 metadata.yaml)");
  std::vector<fs::path> files;
  try {
    const std::string storage = info["storage_identifier"] ? info["storage_identifier"].as<std::string>() : "";
    if (storage != "sqlite3" && storage != "mcap")
      throw Error(metadata, "storage_identifier '" + message_text(storage, 40) + "' is not supported (sqlite3, mcap)");
    const std::string compression = info["compression_format"] ? info["compression_format"].as<std::string>() : "";
    if (!compression.empty())
      throw Error(metadata, "compressed bag (compression_format " + message_text(compression, 40) +
                                ") is not supported; decompress it first (ros2 bag convert)");
    const YAML::Node paths = info["relative_file_paths"];
    if (!paths || !paths.IsSequence() || paths.size() == 0) throw Error(metadata, "no relative_file_paths");
    for (const auto& p : paths) {
      fs::path file = folder / p.as<std::string>();
      // Foxy wrote "<bag>/<bag>_0.db3": relative to the bag's parent.
      if (!fs::exists(file) && fs::exists(folder / fs::path(p.as<std::string>()).filename()))
        file = folder / fs::path(p.as<std::string>()).filename();
      if (!fs::exists(file)) throw Error(metadata, "lists storage file " + message_text(p.as<std::string>()) + ", which is missing");
      files.push_back(file);
    }
  } catch (const YAML::Exception& e) {
    throw Error(metadata, "malformed rosbag2 metadata: " + e.msg);
  }
  return files;
}

rb::Stamp stamp_of_ns(uint64_t ns) {
  return {static_cast<uint32_t>(std::min<uint64_t>(ns / 1000000000u, UINT32_MAX)), static_cast<uint32_t>(ns % 1000000000u)};
}

// ------------------------------------------------------------------ the source

class Rosbag2Source final : public rb::BagSource {
 public:
  Rosbag2Source(fs::path path, const std::vector<fs::path>& files) : path_(std::move(path)) {
    for (const auto& f : files) storages_.push_back(rosbag2::open_storage(f));
  }
  const fs::path& path() const override { return path_; }

  std::vector<rb::Topic> topics() const override {
    std::lock_guard lock(mutex_);
    if (!topics_.empty()) return topics_;
    std::vector<rb::Topic> out;
    for (const auto& storage : storages_)
      for (const auto& t : storage->topics()) {
        auto it = std::find_if(out.begin(), out.end(), [&](const rb::Topic& o) { return o.name == t.name; });
        if (it == out.end()) {
          // Only CDR is decoded here; another serialisation makes the topic an ignored one.
          const auto type = t.serialization_format == "cdr" ? ros2_msgs::type_of(t.type) : rb::MessageType::other;
          out.push_back({t.name, t.type, type, 0});
          it = out.end() - 1;
        }
        it->messages += t.messages;
      }
    topics_ = out;
    return out;
  }

  rb::ImageMeta first_image_meta(const std::string& topic) const override {
    const bool compressed = type_of(topic) == rb::MessageType::compressed_image;
    return first<rb::ImageMeta>(topic, [&](const rosbag2::VisitedMessage& m, const std::string& where) {
      rb::ImageMeta meta = ros2_msgs::image_meta(m.data, compressed, where);
      meta.bag_stamp = stamp_of_ns(m.log_time_ns);
      return meta;
    });
  }
  rb::CompressedData first_compressed(const std::string& topic) const override {
    return first<rb::CompressedData>(topic, [](const rosbag2::VisitedMessage& m, const std::string& where) { return ros2_msgs::compressed_image(m.data, where); });
  }
  rb::CameraInfoData first_camera_info(const std::string& topic) const override {
    return first<rb::CameraInfoData>(topic, [](const rosbag2::VisitedMessage& m, const std::string& where) { return ros2_msgs::camera_info(m.data, where); });
  }

  std::vector<rb::IndexedMessage> index(const std::vector<std::string>& topics) const override {
    std::vector<bool> compressed;
    for (const auto& t : topics) compressed.push_back(type_of(t) == rb::MessageType::compressed_image);
    std::lock_guard lock(mutex_);
    std::vector<rb::IndexedMessage> out;
    for (size_t s = 0; s < storages_.size(); ++s)
      storages_[s]->visit(topics, [&](const rosbag2::VisitedMessage& m) {
        rb::IndexedMessage im;
        im.topic = m.topic;
        im.meta = ros2_msgs::image_meta(m.data, compressed[m.topic], where(s, topics[m.topic]));
        im.meta.bag_stamp = stamp_of_ns(m.log_time_ns);
        im.handle = handles_.size();
        handles_.push_back({s, m.ref, topics[m.topic]});
        out.push_back(std::move(im));
        return true;
      });
    return out;
  }

  rb::ImageData read_image(size_t handle) const override {
    std::lock_guard lock(mutex_);
    const Handle& h = handle_at(handle);
    return ros2_msgs::image(storages_[h.storage]->read(h.ref), where(h.storage, h.topic));
  }
  rb::CompressedData read_compressed(size_t handle) const override {
    std::lock_guard lock(mutex_);
    const Handle& h = handle_at(handle);
    return ros2_msgs::compressed_image(storages_[h.storage]->read(h.ref), where(h.storage, h.topic));
  }

 private:
  struct Handle {
    size_t storage = 0;
    uint64_t ref = 0;
    std::string topic;
  };

  std::string where(size_t storage, const std::string& topic) const {
    return storages_[storage]->path().string() + ":" + topic;
  }
  rb::MessageType type_of(const std::string& topic) const {
    for (const auto& t : topics())
      if (t.name == topic) return t.type;
    return rb::MessageType::other;
  }
  const Handle& handle_at(size_t handle) const {
    if (handle >= handles_.size()) throw Error(path_, "message handle out of range");
    return handles_[handle];
  }
  /// decode(message, where) of the topic's first message, in storage order.
  template <class T, class Decode>
  T first(const std::string& topic, Decode&& decode) const {
    std::lock_guard lock(mutex_);
    for (size_t s = 0; s < storages_.size(); ++s) {
      std::optional<T> out;
      storages_[s]->visit({topic}, [&](const rosbag2::VisitedMessage& m) {
        out = decode(m, where(s, topic));
        return false;
      });
      if (out) return std::move(*out);
    }
    throw Error(path_, "topic " + topic + " has no message");
  }

  fs::path path_;
  std::vector<std::unique_ptr<rosbag2::Storage>> storages_;
  mutable std::vector<rb::Topic> topics_;  ///< merged over the storages, on first use
  mutable std::vector<Handle> handles_;
  mutable std::mutex mutex_;
};

}  // namespace

std::vector<fs::path> rosbag2_storage_files(const fs::path& folder) {
  if (fs::exists(folder / "metadata.yaml")) return listed_files(folder / "metadata.yaml");
  std::vector<fs::path> files;
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file() && is_storage_file(it->path())) files.push_back(it->path());
  if (files.empty()) throw Error(folder, "no metadata.yaml and no .db3 or .mcap file (not a rosbag2 folder)");
  std::sort(files.begin(), files.end(), natural_less);
  spdlog::warn("{}: no metadata.yaml (recording cut off?); reading {} storage file(s) in name order", folder.string(), files.size());
  return files;
}

bool is_rosbag2_folder(const fs::path& folder) {
  if (fs::exists(folder / "metadata.yaml")) {
    std::ifstream in(folder / "metadata.yaml");
    std::string head(4096, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    return head.find("rosbag2_bagfile_information") != std::string::npos;
  }
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file() && is_storage_file(it->path())) return true;
  return false;
}

std::unique_ptr<rb::BagSource> open_rosbag2_source(const fs::path& path) {
  if (fs::is_directory(path)) return std::make_unique<Rosbag2Source>(path, rosbag2_storage_files(path));
  return std::make_unique<Rosbag2Source>(path, std::vector<fs::path>{path});
}

}  // namespace semap::io_detail
