#include "core/paths.hpp"

#include <cstdlib>
#include <fstream>

#include "semap/core/error.hpp"

namespace semap {

std::filesystem::path data_dir(const std::filesystem::path& fallback) {
  if (const char* env = std::getenv("SEMAP_DATA_DIR"); env && *env) return env;
  return fallback;
}

std::filesystem::path models_dir(const std::filesystem::path& fallback) {
  if (const char* env = std::getenv("SEMAP_MODELS_DIR"); env && *env) return env;
  return fallback;
}

void write_file_atomic(const std::filesystem::path& path, const std::string& bytes) {
  write_atomic_with(path, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(path, "cannot open for writing");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) throw Error(path, "write failed (disk full?)");
  });
}

}  // namespace semap
