#include "core/paths.hpp"

#include <fcntl.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>

#include "semap/core/error.hpp"

namespace semap {

namespace fs = std::filesystem;

fs::path data_dir(const fs::path& fallback) {
  if (const char* env = std::getenv("SEMAP_DATA_DIR"); env && *env) return env;
  return fallback;
}

fs::path models_dir(const fs::path& fallback) {
  if (const char* env = std::getenv("SEMAP_MODELS_DIR"); env && *env) return env;
  return fallback;
}

// ------------------------------------------------------------------------------ reading

namespace {

std::string kind_of_mode(mode_t mode) {
  if (S_ISREG(mode)) return "a regular file";
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

/// Why stat() failed, refined with lstat() (a dangling link is ENOENT for stat).
std::string describe_stat_failure(const fs::path& path, int error) {
  struct stat link {};
  if (error == ENOENT && ::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
    std::error_code ec;
    const fs::path target = fs::read_symlink(path, ec);
    return "a dangling symlink (to " + (ec ? std::string("?") : target.string()) + ")";
  }
  switch (error) {
    case ENOENT: return "not found";
    case ELOOP: return "a symlink loop";
    case EACCES: return "not accessible (permission denied)";
    case ENAMETOOLONG: return "a name too long for the file system";
    case ENOTDIR: return "not found (a part of the path is not a folder)";
    default: return std::string("not accessible (") + std::strerror(error) + ")";
  }
}

[[noreturn]] void throw_not_regular(const fs::path& path, std::string_view what, const std::string& is) {
  if (is == "not found") throw Error(path, std::string(what) + " not found");
  throw Error(path, std::string(what) + " is " + is + ", expected a regular file");
}

}  // namespace

std::string describe_path(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return describe_stat_failure(path, errno);
  return kind_of_mode(st.st_mode);
}

bool is_regular_file_path(const fs::path& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

void require_regular_file(const fs::path& path, std::string_view what) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw_not_regular(path, what, describe_stat_failure(path, errno));
  if (!S_ISREG(st.st_mode)) throw_not_regular(path, what, kind_of_mode(st.st_mode));
}

std::string read_regular_file(const fs::path& path, uint64_t max_bytes, std::string_view what) {
  // O_NONBLOCK: opening a FIFO without a writer would otherwise block forever.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) {
    const int error = errno;
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) throw_not_regular(path, what, kind_of_mode(st.st_mode));
    throw_not_regular(path, what, describe_stat_failure(path, error));
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) throw Error(path, std::string("cannot read ") + std::string(what) + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw_not_regular(path, what, kind_of_mode(st.st_mode));
  const auto size = static_cast<uint64_t>(st.st_size);
  if (size > max_bytes)
    throw Error(path, std::string(what) + " is " + std::to_string(size) + " bytes, more than the limit of " +
                          std::to_string(max_bytes) + " bytes");
  std::string bytes(static_cast<size_t>(size), '\0');
  size_t filled = 0;
  while (true) {
    if (filled == bytes.size()) {
      // The file may have grown since fstat: read on, up to the limit.
      if (bytes.size() >= max_bytes + 1) break;
      bytes.resize(std::min<uint64_t>(max_bytes + 1, std::max<uint64_t>(bytes.size() * 2, 4096)));
    }
    const ssize_t n = ::read(fd, bytes.data() + filled, bytes.size() - filled);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw Error(path, std::string("read failed: ") + std::strerror(errno));
    if (n == 0) break;
    filled += static_cast<size_t>(n);
  }
  if (filled > max_bytes)
    throw Error(path, std::string(what) + " grew past the limit of " + std::to_string(max_bytes) + " bytes while read");
  bytes.resize(filled);
  return bytes;
}

// ------------------------------------------------------------------------------ writing

namespace {

constexpr std::string_view kTempMarker = ".semap-tmp-";

uint64_t random_u64() {
  uint64_t value = 0;
  if (::getrandom(&value, sizeof value, 0) != static_cast<ssize_t>(sizeof value)) {
    static std::atomic<uint64_t> counter{0};
    value = (static_cast<uint64_t>(::getpid()) << 32) ^ static_cast<uint64_t>(::time(nullptr)) ^ ++counter * 0x9E3779B97F4A7C15ull;
  }
  return value;
}

// Temp files a second Ctrl-C unlinks (async-signal-safe: fixed slots, atomics only).
struct TempSlot {
  std::atomic<int> state{0};  // 0 free, 1 being changed, 2 holds a path
  char path[PATH_MAX];
};
std::array<TempSlot, 64> g_temp_slots;

}  // namespace

bool is_semap_temp_name(std::string_view filename) {
  return !filename.empty() && filename.front() == '.' && filename.find(kTempMarker) != std::string_view::npos;
}

fs::path create_temp_file_beside(const fs::path& path) {
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  const std::string base = path.filename().string().substr(0, 120);  // NAME_MAX-safe
  for (int attempt = 0; attempt < 16; ++attempt) {
    char suffix[48];
    std::snprintf(suffix, sizeof suffix, "%d-%016llx", static_cast<int>(::getpid()),
                  static_cast<unsigned long long>(random_u64()));
    const fs::path tmp = folder / ("." + base + std::string(kTempMarker) + suffix);
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::close(fd);
      return tmp;
    }
    if (errno == EEXIST) continue;
    throw Error(path, std::string("cannot create a file in ") + folder.string() + ": " + std::strerror(errno));
  }
  throw Error(path, "cannot create a unique temporary file beside it");
}

namespace paths_detail {

void commit_temp(const fs::path& tmp, const fs::path& path) {
  if (::rename(tmp.c_str(), path.c_str()) == 0) return;
  const int error = errno;
  ::unlink(tmp.c_str());
  if (error == EISDIR) throw Error(path, "is a folder; cannot replace it with a file");
  throw Error(path, std::string("cannot write: ") + std::strerror(error));
}

void register_temp(const fs::path& tmp) {
  const std::string& s = tmp.native();
  if (s.size() >= PATH_MAX) return;
  for (auto& slot : g_temp_slots) {
    int expected = 0;
    if (!slot.state.compare_exchange_strong(expected, 1)) continue;
    std::memcpy(slot.path, s.c_str(), s.size() + 1);
    slot.state.store(2);
    return;
  }
}

void unregister_temp(const fs::path& tmp) {
  for (auto& slot : g_temp_slots) {
    if (slot.state.load() != 2 || tmp.native() != slot.path) continue;
    int expected = 2;
    if (slot.state.compare_exchange_strong(expected, 1)) slot.state.store(0);
    return;
  }
}

void unlink_registered_temps_from_signal_handler() {
  for (auto& slot : g_temp_slots)
    if (slot.state.load() == 2) ::unlink(slot.path);
}

}  // namespace paths_detail

void write_file_atomic(const fs::path& path, std::string_view bytes) {
  const fs::path tmp = create_temp_file_beside(path);
  paths_detail::register_temp(tmp);
  const auto fail = [&](const std::string& why) {
    ::unlink(tmp.c_str());
    paths_detail::unregister_temp(tmp);
    throw Error(path, why);
  };
  // Reopen the file created above, never following a link (O_NOFOLLOW) nor creating anew.
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_TRUNC | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) fail(std::string("cannot open for writing: ") + std::strerror(errno));
  size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = errno;
      ::close(fd);
      fail(std::string("write failed (disk full?): ") + std::strerror(error));
    }
    written += static_cast<size_t>(n);
  }
  if (::close(fd) != 0) fail(std::string("write failed (disk full?): ") + std::strerror(errno));
  try {
    paths_detail::commit_temp(tmp, path);
  } catch (...) {
    paths_detail::unregister_temp(tmp);
    throw;
  }
  paths_detail::unregister_temp(tmp);
}

}  // namespace semap
