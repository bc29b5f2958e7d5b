#pragma once
// Helpers shared by all tests: where ../shared lives, temp folders, running the CLI.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace semap::test {

/// ../shared/data (or $SEMAP_DATA_DIR).
std::filesystem::path data_dir();
/// ../shared/models (or $SEMAP_MODELS_DIR).
std::filesystem::path models_dir();
/// A dataset folder under data_dir(); GTEST_SKIPs the calling test when it is absent.
#define SEMAP_REQUIRE_DATA(var, name)                                          \
  const std::filesystem::path var = ::semap::test::data_dir() / (name);         \
  if (!std::filesystem::exists(var)) GTEST_SKIP() << "shared data missing: " << var

/// A fresh empty folder under the system temp dir, removed at destruction.
class TempDir {
 public:
  explicit TempDir(const std::string& tag = "semap_test");
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

/// Path of build/semap.
std::filesystem::path semap_executable();

struct CommandResult {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr together
};
/// Runs a shell command, capturing its output (and its exit code).
CommandResult run_command(const std::string& command);

/// Writes text / bytes to a file (test corpora are generated, never committed).
void write_text(const std::filesystem::path& path, const std::string& text);

}  // namespace semap::test
