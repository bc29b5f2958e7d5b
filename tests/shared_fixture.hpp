#pragma once
// A fixture folder made once per build and shared by the test processes of a run (issue 41).
// ctest runs every test of a suite as a process of its own (gtest_discover_tests), so a suite's
// SetUpTestSuite runs once per test: the 90-frame synthetic dataset of PipelineTest took ~130 s
// per process under ASan+UBSan, for each of its tests. copy_shared_fixture makes the folder
// once, under a lock, and gives each process its own copy of it, so what a test may change is
// still its own.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <system_error>

namespace semap::test {

namespace shared_fixture_detail {

/// Holds an exclusive flock on `path` (created if absent) for its lifetime.
class FileLock {
 public:
  /// `wait` false: takes the lock only if nobody holds it (locked() says whether it did).
  explicit FileLock(const std::filesystem::path& path, bool wait = true)
      : fd_(::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644)) {
    if (fd_ >= 0 && ::flock(fd_, wait ? LOCK_EX : LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~FileLock() {
    if (fd_ >= 0) ::close(fd_);  // closing releases the lock, also when the process dies
  }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  bool locked() const { return fd_ >= 0; }

 private:
  int fd_;
};

/// "<key>-<hash of maker's path>-<hash of its size and modification time>": a rebuilt maker
/// (another generator) never reuses an old folder; the prefix up to the second hash names
/// the older folders of the same maker, which are removed.
inline std::string entry_name(const std::string& key, const std::filesystem::path& maker, std::string* prefix) {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::canonical(maker, ec);
  const auto size = std::filesystem::file_size(exe, ec);
  const auto mtime = std::filesystem::last_write_time(exe, ec).time_since_epoch().count();
  char hashes[64];
  std::snprintf(hashes, sizeof hashes, "-%016zx-", std::hash<std::string>{}(exe.string()));
  *prefix = key + hashes;
  std::snprintf(hashes, sizeof hashes, "%016zx",
                std::hash<std::string>{}(std::to_string(size) + ":" + std::to_string(static_cast<long long>(mtime))));
  return *prefix + hashes;
}

/// Folders unused for this long are another clone's (CI clones each run into a new folder, and
/// the maker's path is part of every name): removed, so the cache does not grow per clone.
constexpr auto kUnusedFor = std::chrono::hours(72);

/// Removes the folders of other makers that nobody used for kUnusedFor, each under its maker's
/// lock taken without waiting (a maker at work keeps its folders).
inline void remove_unused_entries(const std::filesystem::path& root, const std::string& own_prefix) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto now = fs::file_time_type::clock::now();
  for (const auto& lock_file : fs::directory_iterator(root, ec)) {
    const std::string lock_name = lock_file.path().filename().string();
    const size_t suffix = lock_name.size() >= 4 ? lock_name.size() - 4 : std::string::npos;
    if (suffix == std::string::npos || lock_name.compare(suffix, 4, "lock") != 0) continue;
    const std::string prefix = lock_name.substr(0, suffix);
    if (prefix == own_prefix) continue;
    FileLock lock(lock_file.path(), /*wait=*/false);
    if (!lock.locked()) continue;
    for (const auto& entry : fs::directory_iterator(root, ec)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind(prefix, 0) != 0 || name == lock_name) continue;
      const auto used = fs::last_write_time(entry.path(), ec);
      if (!ec && now - used > kUnusedFor) fs::remove_all(entry.path(), ec);
    }
  }
}

}  // namespace shared_fixture_detail

/// Copies into `dest` (which must not exist) the folder that `make` writes at the path it is
/// given, made at most once per build of `maker` (the executable that generates it: the test
/// binary, or build/semap for a CLI-made folder) and kept under the system temp folder
/// (semap-shared-fixtures/). `key` names what `make` makes (its parameters). A `make` that
/// records a gtest failure publishes nothing. Safe across processes (flock); within one
/// process, call it from one thread at a time.
inline void copy_shared_fixture(const std::string& key, const std::filesystem::path& maker,
                                const std::function<void(const std::filesystem::path&)>& make,
                                const std::filesystem::path& dest) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "semap-shared-fixtures";
  fs::create_directories(root);
  std::string prefix;
  const std::string name = shared_fixture_detail::entry_name(key, maker, &prefix);
  const fs::path entry = root / name;
  {
    shared_fixture_detail::FileLock lock(root / (prefix + "lock"));
    ASSERT_TRUE(lock.locked()) << "cannot lock " << root;
    if (!fs::exists(entry)) {
      const fs::path staging = root / (name + ".staging");
      fs::remove_all(staging);  // a process that died while making it (the lock is ours now)
      make(staging);
      if (::testing::Test::HasFailure() || !fs::exists(staging)) {
        std::error_code ec;
        fs::remove_all(staging, ec);
        FAIL() << "making the shared fixture " << key << " failed";
      }
      fs::rename(staging, entry);  // published whole, or not at all
      for (const auto& other : fs::directory_iterator(root)) {
        const std::string other_name = other.path().filename().string();
        if (other_name.rfind(prefix, 0) == 0 && other_name != name && other_name != prefix + "lock")
          fs::remove_all(other.path());  // made by an earlier build of the same maker
      }
      shared_fixture_detail::remove_unused_entries(root, prefix);
    }
    std::error_code ec;
    fs::last_write_time(entry, fs::file_time_type::clock::now(), ec);  // in use: kept by other clones' sweeps
  }
  fs::copy(entry, dest, fs::copy_options::recursive);
}

}  // namespace semap::test
