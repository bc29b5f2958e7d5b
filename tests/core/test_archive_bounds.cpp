// Issue 44, class 2: a map.semap whose sections declare more inflated bytes than the file can
// plausibly hold (kMaxMapInflation x its size + kMapInflationAllowanceBytes) is refused before
// any section is decompressed; real maps well inside the bound still read.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "core/archive.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;

uint64_t fnv1a(std::string_view data) {  // the archive's checksum (archive.cpp)
  uint64_t h = 1469598103934665603ULL;
  for (const char c : data) {
    h ^= static_cast<uint8_t>(c);
    h *= 1099511628211ULL;
  }
  return h;
}

/// A version-3 archive with one section `name` declaring `raw_bytes` and storing `stored`,
/// with a valid checksum (so the reader gets past it to the section sizes).
std::string archive_bytes(const std::vector<std::pair<uint64_t, std::string>>& sections) {
  ByteWriter w;
  w.put_bytes("SEMAPMAP", 8);
  w.put(kMapArchiveVersion);
  w.put(static_cast<uint32_t>(sections.size()));
  int k = 0;
  for (const auto& [raw_bytes, stored] : sections) {
    const std::string name = "section" + std::to_string(k++);
    w.put(static_cast<uint32_t>(name.size()));
    w.put_bytes(name.data(), name.size());
    w.put(raw_bytes);
    w.put(static_cast<uint64_t>(stored.size()));
    w.put_bytes(stored.data(), stored.size());
  }
  std::string bytes = w.bytes();
  const uint64_t sum = fnv1a(std::string_view(bytes).substr(12));
  bytes.append(reinterpret_cast<const char*>(&sum), 8);
  return bytes;
}

void write(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary).write(bytes.data(), bytes.size()); }

std::string error_of(const fs::path& p) {
  try {
    read_map_archive(p);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(MapArchiveBounds, SectionsInflatingFarBeyondTheFileAreRefusedBeforeAllocating) {
  test::TempDir tmp("semap_archive_bounds");
  const std::string stored(2 << 20, 'x');  // 2 MB: DEFLATE's 1032:1 would allow 2 GB
  const fs::path one = tmp.path() / "one.semap";
  write(one, archive_bytes({{uint64_t{3} << 29, stored}}));  // 1.5 GiB in one section
  const std::string e1 = error_of(one);
  EXPECT_NE(e1.find(one.string()), std::string::npos) << e1;
  EXPECT_NE(e1.find("sections declare more than"), std::string::npos) << e1;
  // Many sections, each under the ratio, together over it; the sum cannot wrap.
  std::vector<std::pair<uint64_t, std::string>> many(40, {uint64_t{60} << 20, std::string(64 << 10, 'y')});
  many.push_back({~uint64_t{0}, "z"});
  const fs::path split = tmp.path() / "split.semap";
  write(split, archive_bytes(many));
  const std::string e2 = error_of(split);
  EXPECT_NE(e2.find("sections declare more than"), std::string::npos) << e2;
}

TEST(MapArchiveBounds, HighlyCompressibleSmallMapsStillRead) {
  // 32 MB of zeros (a blank label image stack) compresses ~1000:1 and is inside the allowance.
  test::TempDir tmp("semap_archive_bounds");
  const fs::path p = tmp.path() / "zeros.semap";
  write_map_archive(p, {{"labels", std::string(32 << 20, '\0')}, {"tsdf", "voxels"}});
  const ArchiveSections sections = read_map_archive(p);
  ASSERT_EQ(sections.size(), 2u);
  EXPECT_EQ(sections.at("labels").size(), size_t{32} << 20);
}

}  // namespace
}  // namespace semap
