#pragma once
// Where shared data and models live: ../shared/{data,models} beside the checkout, overridable
// with SEMAP_DATA_DIR / SEMAP_MODELS_DIR.
#include <filesystem>

namespace semap {

/// $SEMAP_DATA_DIR, else `fallback` (callers pass the build-time ../shared/data).
std::filesystem::path data_dir(const std::filesystem::path& fallback);
/// $SEMAP_MODELS_DIR, else `fallback`.
std::filesystem::path models_dir(const std::filesystem::path& fallback);

/// Writes `bytes` to `path` atomically (temp file in the same folder + rename), so an
/// interrupted run never leaves a half-written file that looks complete.
void write_file_atomic(const std::filesystem::path& path, const std::string& bytes);

/// Runs `writer(tmp_path)` then renames tmp_path to `path`; removes tmp_path on failure.
template <class F>
void write_atomic_with(const std::filesystem::path& path, F&& writer);

}  // namespace semap

#include <string>
#include <system_error>

namespace semap {
template <class F>
void write_atomic_with(const std::filesystem::path& path, F&& writer) {
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  try {
    writer(tmp);
    std::filesystem::rename(tmp, path);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
}
}  // namespace semap
