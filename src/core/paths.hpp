#pragma once
// Where shared data and models live (../shared/{data,models} beside the checkout, overridable
// with SEMAP_DATA_DIR / SEMAP_MODELS_DIR), and the two file primitives every reader and writer
// goes through (issue 22):
//  - read_regular_file(): opens only regular files (never a FIFO, /dev/zero, a socket or a
//    folder: those hang or never end), with a size limit, and says what a path is when it is
//    not a readable file ("is a folder", "is a dangling symlink", "is a symlink loop", ...);
//  - write_file_atomic() / write_atomic_with(): a fresh, unguessable temporary name created with
//    O_CREAT|O_EXCL|O_NOFOLLOW beside the target, renamed over it at the end, so neither a
//    planted symlink nor an interruption can redirect or half-write an output.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace semap {

/// $SEMAP_DATA_DIR, else `fallback` (callers pass the build-time ../shared/data).
std::filesystem::path data_dir(const std::filesystem::path& fallback);
/// $SEMAP_MODELS_DIR, else `fallback`.
std::filesystem::path models_dir(const std::filesystem::path& fallback);

// ------------------------------------------------------------------------------ reading

/// Size limits of read_regular_file() per kind of input.
inline constexpr uint64_t kMaxTextFileBytes = uint64_t{256} << 20;   ///< lists, configs, trajectories, JSON
inline constexpr uint64_t kMaxImageFileBytes = uint64_t{1} << 30;    ///< one image
inline constexpr uint64_t kMaxMeshFileBytes = uint64_t{8} << 30;     ///< PLY meshes / point clouds
inline constexpr uint64_t kMaxModelFileBytes = uint64_t{4} << 30;    ///< ONNX models

/// What a path is, without opening it: "a regular file", "a folder", "a FIFO (named pipe)",
/// "a character device", "a socket", "a dangling symlink (to TARGET)", "a symlink loop",
/// "not found", "not accessible (permission denied)", "a name too long for the file system".
std::string describe_path(const std::filesystem::path& path);
/// True when `path` is (or links to) a regular file.
bool is_regular_file_path(const std::filesystem::path& path);
/// Throws Error(path, "<what> is <describe_path>, expected a regular file") unless `path` is
/// (or links to) a regular file. `what` names the role: "list file", "image", "config file".
void require_regular_file(const std::filesystem::path& path, std::string_view what = "file");
/// The whole file, opened non-blocking (a FIFO cannot hang the open) and checked with fstat
/// to be a regular file of at most `max_bytes` (a file growing while read is cut there and
/// refused). Errors name the file and say what it is.
std::string read_regular_file(const std::filesystem::path& path, uint64_t max_bytes,
                              std::string_view what = "file");

// ------------------------------------------------------------------------------ writing

/// Creates a new empty file beside `path` named ".NAME.semap-tmp-PID-RANDOM" with
/// O_CREAT|O_EXCL|O_NOFOLLOW (mode 0644) and returns its name; throws naming `path` when the
/// folder is not writable. Nothing that exists there beforehand (a symlink, a file) is reused.
std::filesystem::path create_temp_file_beside(const std::filesystem::path& path);
/// True for names made by create_temp_file_beside() (cleanup of interrupted runs).
bool is_semap_temp_name(std::string_view filename);

/// Writes `bytes` to `path` atomically (exclusive temp file in the same folder + rename), so an
/// interrupted run never leaves a half-written file that looks complete.
void write_file_atomic(const std::filesystem::path& path, std::string_view bytes);

/// Runs `writer(tmp_path)` then renames tmp_path to `path`; removes tmp_path on failure.
/// tmp_path exists (created exclusively, empty) when `writer` runs: the writer opens it by name
/// and truncates it; its unguessable name cannot have been planted beforehand.
template <class F>
void write_atomic_with(const std::filesystem::path& path, F&& writer);

namespace paths_detail {
/// rename(tmp, path), naming `path` in the error; removes tmp when the rename fails.
void commit_temp(const std::filesystem::path& tmp, const std::filesystem::path& path);
/// Registers a live temp file so a fatal second Ctrl-C can unlink it (io/output_folder.hpp).
void register_temp(const std::filesystem::path& tmp);
void unregister_temp(const std::filesystem::path& tmp);
/// Unlinks every registered temp file; async-signal-safe (called from the signal handler).
void unlink_registered_temps_from_signal_handler();
}  // namespace paths_detail

}  // namespace semap

#include <system_error>

namespace semap {
template <class F>
void write_atomic_with(const std::filesystem::path& path, F&& writer) {
  const std::filesystem::path tmp = create_temp_file_beside(path);
  paths_detail::register_temp(tmp);
  try {
    writer(tmp);
    paths_detail::commit_temp(tmp, path);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    paths_detail::unregister_temp(tmp);
    throw;
  }
  paths_detail::unregister_temp(tmp);
}
}  // namespace semap
