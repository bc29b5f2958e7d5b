#pragma once
// Shared by the libFuzzer targets (fuzz/README.md): a per-process scratch file for parsers that
// read from a path, and seed writing. A parser may reject any input with semap::Error (one line
// naming the file); every other exception escapes and libFuzzer reports it as a crash, as it
// does for ASan/UBSan reports and timeouts.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace semap::fuzz {

/// A scratch folder for this process (in /dev/shm when it exists: no disk writes per input).
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path base = std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
    auto d = base / ("semap_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] { std::error_code ec; std::filesystem::remove_all(scratch_dir(), ec); });
    return d;
  }();
  return dir;
}

inline void write_bytes(const std::filesystem::path& p, const uint8_t* data, size_t size) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}
inline void write_bytes(const std::filesystem::path& p, const std::string& bytes) {
  write_bytes(p, reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
}

/// The fuzz input written to scratch_dir()/name; returns the path.
inline std::filesystem::path input_file(const std::string& name, const uint8_t* data, size_t size) {
  auto p = scratch_dir() / name;
  write_bytes(p, data, size);
  return p;
}

/// Seeds: when SEMAP_FUZZ_SEED_DIR is set, LLVMFuzzerInitialize writes valid inputs made by
/// the project's own writers there (scripts/ci-fuzz.sh passes the corpus folder), so no binary
/// seed is committed and seeds follow format changes.
inline void write_seed(const std::string& name, const std::string& bytes) {
  const char* dir = std::getenv("SEMAP_FUZZ_SEED_DIR");
  if (!dir || !*dir) return;
  std::filesystem::create_directories(dir);
  write_bytes(std::filesystem::path(dir) / name, bytes);
}

inline std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// A map.semap input written to scratch_dir()/map.semap with its checksum (core/archive.hpp:
/// FNV-1a 64 of the bytes after the 12-byte head) appended as write_map_archive does, so that the
/// fuzzer reaches the section table and the sections instead of stopping at the checksum; every
/// 64th input is written as it is (the checksum and truncation paths). Returns the path.
inline std::filesystem::path map_input_file(const uint8_t* data, size_t size) {
  const auto fnv1a = [](const uint8_t* p, size_t n) {
    uint64_t h = 1469598103934665603ULL;
    for (size_t i = 0; i < n; ++i) {
      h ^= p[i];
      h *= 1099511628211ULL;
    }
    return h;
  };
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (size >= 12 && fnv1a(data, size) % 64 != 0) {
    const uint64_t sum = fnv1a(data + 12, size - 12);
    bytes.append(reinterpret_cast<const char*>(&sum), sizeof sum);
  }
  return input_file("map.semap", reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
}

}  // namespace semap::fuzz
