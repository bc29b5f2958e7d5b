#pragma once
// map.semap container (issue 19): a versioned, checksummed file of named sections, one per
// stage (tsdf, tracking, objects, object_views, camera, config), each encoded by its own stage;
// a reader skips a section it does not know and tolerates an optional one being absent.
//   "SEMAPMAP" | u32 version | u32 section count | per section: u32 name bytes, name,
//   u64 payload bytes, u64 stored bytes, the payload DEFLATE-compressed (libdeflate) |
//   u64 FNV-1a of everything after the version
// Version 2 stored the payloads uncompressed (no stored-bytes field); it is still read.
// Sections are written in name order, and compression is deterministic, so equal contents give
// byte-identical files. Little-endian
// PODs throughout (ByteWriter / ByteReader). Every read error names the file.
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "semap/core/error.hpp"

namespace semap {

/// Version 1 held the TSDF only; version 2 is the sectioned map; version 3 compresses its
/// sections (keyframe images and voxels shrink 3-4x).
inline constexpr uint32_t kMapArchiveVersion = 3;

using ArchiveSections = std::map<std::string, std::string>;

/// Issue 44: the sections of a map file together inflate to at most
/// kMapInflationAllowanceBytes + kMaxMapInflation x the file's size, checked against the
/// declared sizes before any section is decompressed. Real maps shrink 3-4x (keyframe images,
/// voxels); DEFLATE itself allows ~1032:1, so a 2 MB file could otherwise claim 2 GB.
inline constexpr uint64_t kMaxMapInflation = 64;
inline constexpr uint64_t kMapInflationAllowanceBytes = uint64_t{64} << 20;

/// Writes the archive atomically (core/paths.hpp).
void write_map_archive(const std::filesystem::path& path, const ArchiveSections& sections);
/// Reads and checks the whole archive: magic, version (an older or newer one is an error naming
/// both), section table, checksum.
ArchiveSections read_map_archive(const std::filesystem::path& path);
/// The named section; throws Error(path, "has no <name> section ...") when it is absent.
const std::string& archive_section(const ArchiveSections& sections, const std::string& name,
                                   const std::filesystem::path& path);

class ByteWriter {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void put_bytes(const void* data, size_t n) { bytes_.append(static_cast<const char*>(data), n); }
  void put_string(std::string_view s) {
    put(static_cast<uint64_t>(s.size()));
    bytes_.append(s);
  }
  /// rows, cols, type, then the pixels row by row (continuous or not).
  void put_mat(const cv::Mat& m);
  void reserve(size_t n) { bytes_.reserve(n); }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

class ByteReader {
 public:
  ByteReader(std::string_view bytes, std::filesystem::path path, std::string section)
      : bytes_(bytes), path_(std::move(path)), section_(std::move(section)) {}
  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T value;
    read(&value, sizeof(T));
    return value;
  }
  void read(void* dst, size_t n) {
    if (n > bytes_.size() - pos_) fail("truncated");
    std::memcpy(dst, bytes_.data() + pos_, n);
    pos_ += n;
  }
  /// The next n bytes without copying them (a view into the reader's bytes).
  std::string_view get_view(size_t n) {
    if (n > bytes_.size() - pos_) fail("truncated");
    pos_ += n;
    return bytes_.substr(pos_ - n, n);
  }
  std::string get_string();
  /// A count of items of `item_bytes` each that must fit in what is left (no huge allocations
  /// from a corrupt count).
  size_t get_count(size_t item_bytes);
  cv::Mat get_mat();
  bool at_end() const { return pos_ == bytes_.size(); }
  /// Throws unless every byte was read.
  void expect_end() const;
  [[noreturn]] void fail(const std::string& what) const;

 private:
  std::string_view bytes_;
  size_t pos_ = 0;
  std::filesystem::path path_;
  std::string section_;
};

}  // namespace semap
