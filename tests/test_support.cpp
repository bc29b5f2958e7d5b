#include "test_support.hpp"

#include <array>
#include <cstdlib>
#include <string_view>
#include <cstdio>
#include <fstream>
#include <random>
#include <sys/wait.h>

#include "core/paths.hpp"

#if defined(__SANITIZE_THREAD__)
#include <tbb/global_control.h>
namespace {
// ThreadSanitizer cannot see oneTBB's internal synchronisation (Debian's libtbb is not built
// with TSan) and reports its work stealing (range splitting, stolen-task flags) as races. Under
// TSan the TBB loops run on the calling thread, so what is checked is our own concurrency:
// pipeline stage threads, the async segmenter, the tracker's loop-closure worker.
const tbb::global_control tsan_serial_tbb(tbb::global_control::max_allowed_parallelism, 1);
}  // namespace
#endif

namespace semap::test {

bool in_ci() {
  const char* ci = std::getenv("CI");
  return ci && std::string_view(ci) == "true";
}

std::filesystem::path data_dir() { return semap::data_dir(std::filesystem::path(SEMAP_SHARED_DIR) / "data"); }
std::filesystem::path models_dir() {
  return semap::models_dir(std::filesystem::path(SEMAP_SHARED_DIR) / "models");
}

TempDir::TempDir(const std::string& tag) {
  std::random_device rd;
  path_ = std::filesystem::temp_directory_path() / (tag + "_" + std::to_string(rd()) + std::to_string(rd()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::filesystem::path semap_executable() { return std::filesystem::path(SEMAP_BINARY_DIR) / "semap"; }

std::string shell_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

CommandResult run_command(const std::string& command) {
  CommandResult result;
  const std::string full = command + " 2>&1";
  FILE* pipe = popen(full.c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buf{};
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) result.output.append(buf.data(), n);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

}  // namespace semap::test
