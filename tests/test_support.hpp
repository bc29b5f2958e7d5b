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
/// True when the environment says CI=true: a missing prerequisite (shared data, a model, a
/// package the install script provides) then fails the test instead of skipping it, so CI
/// cannot go green with the real-data tests not run (issue 21).
bool in_ci();
/// Skips the calling test with `message` (a stream expression), or fails it under CI=true.
#define SEMAP_SKIP_OR_FAIL(message)                                                          \
  do {                                                                                       \
    if (::semap::test::in_ci()) GTEST_FAIL() << message << " (CI=true: this must not be missing)"; \
    GTEST_SKIP() << message;                                                                 \
  } while (0)
/// A dataset folder under data_dir(); skips (under CI fails) the calling test when it is absent.
#define SEMAP_REQUIRE_DATA(var, name)                                  \
  const std::filesystem::path var = ::semap::test::data_dir() / (name); \
  if (!std::filesystem::exists(var))                                   \
  SEMAP_SKIP_OR_FAIL("shared data missing: " << var << " (set SEMAP_DATA_DIR)")
/// A model file under models_dir(); the same rule.
#define SEMAP_REQUIRE_MODEL(var, name)                                   \
  const std::filesystem::path var = ::semap::test::models_dir() / (name); \
  if (!std::filesystem::exists(var))                                     \
  SEMAP_SKIP_OR_FAIL("model missing: " << var << " (set SEMAP_MODELS_DIR)")

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
/// `text` as one single-quoted shell word.
std::string shell_quote(const std::string& text);
/// Runs a shell command, capturing its output (and its exit code).
CommandResult run_command(const std::string& command);

/// Writes text / bytes to a file (test corpora are generated, never committed).
void write_text(const std::filesystem::path& path, const std::string& text);

}  // namespace semap::test
