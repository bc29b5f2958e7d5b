#include "core/archive.hpp"

#include <libdeflate.h>

#include <algorithm>
#include <memory>

#include "core/paths.hpp"

namespace semap {
namespace {

constexpr char kMagic[8] = {'S', 'E', 'M', 'A', 'P', 'M', 'A', 'P'};
constexpr uint64_t kMaxArchiveBytes = uint64_t{16} << 30;

uint64_t fnv1a(std::string_view data) {
  uint64_t h = 1469598103934665603ULL;
  for (const char c : data) {
    h ^= static_cast<uint8_t>(c);
    h *= 1099511628211ULL;
  }
  return h;
}

constexpr uint32_t kUncompressedVersion = 2;  // still read
/// libdeflate level: 4 compresses keyframe images about as well as 9 at several times the speed.
constexpr int kCompressionLevel = 4;
/// DEFLATE cannot expand more than ~1032:1: a larger declared size is a corrupt (or hostile) file.
constexpr uint64_t kMaxDeflateRatio = 1032;

std::string compress(std::string_view raw) {
  std::unique_ptr<libdeflate_compressor, decltype(&libdeflate_free_compressor)> c(
      libdeflate_alloc_compressor(kCompressionLevel), &libdeflate_free_compressor);
  if (!c) throw Error("map file", "out of memory for the compressor");
  std::string out(libdeflate_deflate_compress_bound(c.get(), raw.size()), '\0');
  const size_t n = libdeflate_deflate_compress(c.get(), raw.data(), raw.size(), out.data(), out.size());
  if (n == 0 && !raw.empty()) throw Error("map file", "compression failed");
  out.resize(n);
  return out;
}

std::string decompress(std::string_view stored, uint64_t raw_bytes, const ByteReader& r) {
  if (raw_bytes > kMaxDeflateRatio * stored.size() + 64 || raw_bytes > kMaxArchiveBytes)
    r.fail("a section declares " + std::to_string(raw_bytes) + " bytes from " + std::to_string(stored.size()));
  std::unique_ptr<libdeflate_decompressor, decltype(&libdeflate_free_decompressor)> d(
      libdeflate_alloc_decompressor(), &libdeflate_free_decompressor);
  std::string raw(raw_bytes, '\0');
  size_t got = 0;
  if (!d || libdeflate_deflate_decompress(d.get(), stored.data(), stored.size(), raw.data(), raw.size(), &got) !=
                LIBDEFLATE_SUCCESS ||
      got != raw_bytes)
    r.fail("a section does not decompress");
  return raw;
}

}  // namespace

void write_map_archive(const std::filesystem::path& path, const ArchiveSections& sections) {
  size_t total = 32;
  for (const auto& [name, payload] : sections) total += 12 + name.size() + payload.size();
  ByteWriter w;
  w.reserve(total);
  w.put_bytes(kMagic, 8);
  w.put(kMapArchiveVersion);
  const size_t checked_from = w.bytes().size();
  w.put(static_cast<uint32_t>(sections.size()));
  for (const auto& [name, payload] : sections) {
    const std::string stored = compress(payload);
    w.put(static_cast<uint32_t>(name.size()));
    w.put_bytes(name.data(), name.size());
    w.put(static_cast<uint64_t>(payload.size()));
    w.put(static_cast<uint64_t>(stored.size()));
    w.put_bytes(stored.data(), stored.size());
  }
  w.put(fnv1a(std::string_view(w.bytes()).substr(checked_from)));
  write_file_atomic(path, w.bytes());
}

ArchiveSections read_map_archive(const std::filesystem::path& path) {
  const std::string bytes = read_regular_file(path, kMaxArchiveBytes, "map file");
  if (bytes.size() < 8 + 4 || std::memcmp(bytes.data(), kMagic, 8) != 0)
    throw Error(path, "not a semap map file (bad magic or truncated)");
  uint32_t version;
  std::memcpy(&version, bytes.data() + 8, 4);
  if (version != kMapArchiveVersion && version != kUncompressedVersion)
    throw Error(path, "map format version " + std::to_string(version) + ", this build reads versions " +
                          std::to_string(kUncompressedVersion) + "-" + std::to_string(kMapArchiveVersion) +
                          (version < kMapArchiveVersion ? " (an older semap wrote it: map the recording again)" : ""));
  const size_t checked_from = 12;
  if (bytes.size() < checked_from + 4 + 8) throw Error(path, "truncated map file");
  uint64_t stored_sum;
  std::memcpy(&stored_sum, bytes.data() + bytes.size() - 8, 8);
  const std::string_view body = std::string_view(bytes).substr(checked_from, bytes.size() - 8 - checked_from);
  if (fnv1a(body) != stored_sum) throw Error(path, "checksum mismatch (corrupt or truncated map file)");
  ByteReader r(body, path, "section table");
  // The whole table first, so that the declared sizes are checked before anything is inflated.
  struct Entry {
    std::string name;
    uint64_t raw_bytes = 0;
    std::string_view stored;
  };
  std::vector<Entry> table;
  const uint64_t max_raw_bytes = kMapInflationAllowanceBytes + kMaxMapInflation * bytes.size();
  uint64_t raw_total = 0;
  const uint32_t count = r.get<uint32_t>();
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t name_bytes = r.get<uint32_t>();
    if (name_bytes == 0 || name_bytes > 64) r.fail("bad section name length " + std::to_string(name_bytes));
    Entry e;
    e.name.resize(name_bytes);
    r.read(e.name.data(), name_bytes);
    e.raw_bytes = version == kUncompressedVersion ? 0 : r.get<uint64_t>();
    e.stored = r.get_view(r.get_count(1));
    raw_total += std::min(e.raw_bytes, max_raw_bytes + 1);  // no wrap-around
    if (raw_total > max_raw_bytes)
      r.fail("sections declare more than " + std::to_string(max_raw_bytes) + " bytes inflated (" +
             std::to_string(kMaxMapInflation) + " x the file's " + std::to_string(bytes.size()) + " bytes + " +
             std::to_string(kMapInflationAllowanceBytes >> 20) + " MiB): not a map semap wrote");
    table.push_back(std::move(e));
  }
  ArchiveSections sections;
  for (Entry& e : table) {
    std::string payload = version == kUncompressedVersion ? std::string(e.stored) : decompress(e.stored, e.raw_bytes, r);
    if (!sections.emplace(std::move(e.name), std::move(payload)).second) r.fail("a section appears twice");
  }
  r.expect_end();
  return sections;
}

const std::string& archive_section(const ArchiveSections& sections, const std::string& name,
                                   const std::filesystem::path& path) {
  const auto it = sections.find(name);
  if (it == sections.end()) throw Error(path, "has no '" + name + "' section (not a complete semap map)");
  return it->second;
}

void ByteWriter::put_mat(const cv::Mat& m) {
  put(static_cast<int32_t>(m.rows));
  put(static_cast<int32_t>(m.cols));
  put(static_cast<int32_t>(m.type()));
  const size_t row_bytes = m.cols * m.elemSize();
  for (int r = 0; r < m.rows; ++r) put_bytes(m.ptr(r), row_bytes);
}

std::string ByteReader::get_string() {
  const size_t n = get_count(1);
  std::string s(n, '\0');
  read(s.data(), n);
  return s;
}

size_t ByteReader::get_count(size_t item_bytes) {
  const uint64_t n = get<uint64_t>();
  if (item_bytes > 0 && n > (bytes_.size() - pos_) / item_bytes) fail("truncated (a count of " + std::to_string(n) + ")");
  return static_cast<size_t>(n);
}

cv::Mat ByteReader::get_mat() {
  const int32_t rows = get<int32_t>(), cols = get<int32_t>(), type = get<int32_t>();
  if (rows < 0 || cols < 0 || rows > 100000 || cols > 100000 || CV_MAT_DEPTH(type) > CV_16F || CV_MAT_CN(type) > 4)
    fail("bad image header " + std::to_string(rows) + "x" + std::to_string(cols));
  cv::Mat m(rows, cols, type);
  const size_t row_bytes = static_cast<size_t>(cols) * m.elemSize();
  if (row_bytes > 0 && static_cast<size_t>(rows) > (bytes_.size() - pos_) / row_bytes) fail("truncated image");
  for (int r = 0; r < rows; ++r) read(m.ptr(r), row_bytes);
  return m;
}

void ByteReader::expect_end() const {
  if (pos_ != bytes_.size()) fail(std::to_string(bytes_.size() - pos_) + " unexpected bytes at the end");
}

void ByteReader::fail(const std::string& what) const {
  throw Error(path_, "map file, " + section_ + ": " + what + " (corrupt map file)");
}

}  // namespace semap
