#pragma once
// Helpers of the reliability tests (issues 8, 22): files, TUM-style lists, the `semap` CLI under
// a time limit, and the checks every bad input shares (one "semap: error:" line, no crash).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <Eigen/Core>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "io/output_folder.hpp"
#include "shared_fixture.hpp"
#include "test_support.hpp"

namespace semap::test {

namespace fs = std::filesystem;

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
inline void spit(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

/// Lines of a TUM-style list without comments.
inline std::vector<std::string> data_lines(const fs::path& list) {
  std::vector<std::string> out;
  std::istringstream in(slurp(list));
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') out.push_back(line);
  return out;
}
inline std::string join_lines(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}
/// The file named by field `field` (after the timestamp) of data line k of a list.
inline fs::path listed(const fs::path& list, size_t k, size_t field = 1) {
  std::istringstream in(data_lines(list).at(k));
  std::string tok;
  for (size_t i = 0; i <= field; ++i) in >> tok;
  return list.parent_path() / tok;
}

inline std::string sh_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}
inline std::string sh_quote(const fs::path& p) { return sh_quote(p.string()); }

/// Lines of the output that start with "semap: error:".
inline size_t error_lines(const std::string& output) {
  size_t n = 0;
  std::istringstream in(output);
  for (std::string line; std::getline(in, line);)
    if (line.rfind("semap: error:", 0) == 0) ++n;
  return n;
}

inline ::testing::AssertionResult no_crash_report(const std::string& output) {
  for (const char* bad : {"Sanitizer", "runtime error:", "terminate called", "Segmentation fault", "Aborted", "core dumped"})
    if (output.find(bad) != std::string::npos) return ::testing::AssertionFailure() << "crash/sanitizer report:\n" << output;
  return ::testing::AssertionSuccess();
}

/// Runs `semap ARGS...` with a time limit (a hang fails as exit 124).
inline CommandResult run_semap(const std::vector<std::string>& args, int limit_s = 120) {
  std::string cmd = "timeout " + std::to_string(limit_s) + " " + sh_quote(semap_executable());
  for (const auto& a : args) cmd += " " + sh_quote(a);
  return run_command(cmd);
}

/// A failing command: exit 1, exactly one error line, naming every string of `must_name`.
inline void expect_one_line_error(const CommandResult& r, const std::vector<std::string>& must_name) {
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(error_lines(r.output), 1u) << r.output;
  for (const auto& name : must_name)
    EXPECT_NE(r.output.find(name), std::string::npos) << "error does not name '" << name << "':\n" << r.output;
  EXPECT_TRUE(no_crash_report(r.output));
}

/// Files (relative paths, sorted) under `dir`, symlinks listed as files, without following them.
/// Also while semap changes the folder (the signal tests poll it during a run): entries that
/// vanish meanwhile are skipped, paths are made relative lexically, nothing throws.
inline std::vector<std::string> tree(const fs::path& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(dir, ec))) return out;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    std::error_code entry_ec;
    const bool folder = it->is_directory(entry_ec) && !it->is_symlink(entry_ec);
    if (!entry_ec && !folder) out.push_back(it->path().lexically_relative(dir).string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// Contents of every file under a folder (relative path -> bytes; a symlink -> its target) or
/// of a single file (key ""), to prove that nothing changed.
inline std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  if (fs::is_regular_file(fs::symlink_status(dir))) return {{"", slurp(dir)}};
  for (const auto& f : tree(dir))
    files[f] = fs::is_symlink(dir / f) ? "-> " + fs::read_symlink(dir / f).string() : slurp(dir / f);
  return files;
}
/// The names that differ between two snapshots ("" when none): added, removed or changed.
inline std::string changes(const std::map<std::string, std::string>& before,
                           const std::map<std::string, std::string>& after) {
  std::string out;
  for (const auto& [name, bytes] : after) {
    const auto it = before.find(name);
    if (it == before.end()) out += " added:" + name;
    else if (it->second != bytes) out += " changed:" + name;
  }
  for (const auto& [name, bytes] : before)
    if (!after.count(name)) out += " removed:" + name;
  return out;
}

/// Files of an output folder without semap's bookkeeping (marker, manifests, staging, temps).
inline std::set<std::string> visible(const fs::path& dir) {
  std::set<std::string> out;
  for (const auto& f : tree(dir))
    if (!OutputFolder::is_internal_name(fs::path(f).begin()->string())) out.insert(f);
  return out;
}

/// Adds `offset` (metres) to every translation of a TUM trajectory file: georeferenced ground truth.
inline void georeference(const fs::path& trajectory, const Eigen::Vector3d& offset) {
  std::vector<std::string> lines = data_lines(trajectory);
  for (auto& line : lines) {
    std::istringstream in(line);
    double t, x, y, z;
    std::string rest;
    in >> t >> x >> y >> z;
    std::getline(in, rest);
    char buffer[160];
    std::snprintf(buffer, sizeof buffer, "%.6f %.9f %.9f %.9f", t, x + offset.x(), y + offset.y(), z + offset.z());
    line = buffer + rest;
  }
  spit(trajectory, join_lines(lines));
}

/// `semap ARGS...` started in the background, stdout and stderr into `log`.
inline pid_t spawn_semap(const std::vector<std::string>& args, const fs::path& log) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    const std::string exe = semap_executable().string();
    std::vector<char*> argv{const_cast<char*>(exe.c_str())};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(exe.c_str(), argv.data());
    ::_exit(127);
  }
  return pid;
}

/// Exit code of `pid` (128 + signal when a signal ended it), -1 after `timeout_s` (then killed).
inline int wait_exit(pid_t pid, double timeout_s) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > until) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// Waits until `log` contains `text`; false after `timeout_s`.
inline bool wait_for_text(const fs::path& log, const std::string& text, double timeout_s) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < until) {
    if (slurp(log).find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

/// A small `semap synth` dataset (12 frames, 160x120, 4 objects) at `dir`: a copy of one made
/// once per build of build/semap, not once per test process (tests/shared_fixture.hpp).
inline void make_small_dataset(const fs::path& dir) {
  copy_shared_fixture("cli_12_frames_seed_2", semap_executable(), [](const fs::path& to) {
    const auto r = run_semap({"synth", "--out", to.string(), "--frames", "12", "--seed", "2", "--objects", "4",
                              "--width", "160", "--height", "120"});
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }, dir);
}

/// A suite of CLI tests over one small dataset made once (make_small_dataset) in a temp folder.
class CliSuite : public ::testing::Test {
 protected:
  static void make_suite(const std::string& tag) {
    tmp_ = new TempDir(tag);
    make_small_dataset(clean());
  }
  static void TearDownTestSuite() {
    delete tmp_;
    tmp_ = nullptr;
  }
  static fs::path clean() { return tmp_->path() / "clean"; }
  static fs::path path(const std::string& name) { return tmp_->path() / name; }
  /// A fresh copy of the clean dataset named `name`.
  static fs::path copy(const std::string& name) {
    const fs::path dir = path(name);
    fs::remove_all(dir);
    fs::copy(clean(), dir, fs::copy_options::recursive);
    return dir;
  }
  /// `semap run DATASET --out OUT` with ground-truth poses and labels, 5 cm voxels, one thread,
  /// then `extra` (which may name another --segmenter).
  static std::vector<std::string> run_args(const fs::path& dataset, const fs::path& out,
                                           std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"run", dataset.string(), "--out", out.string(), "--poses", "groundtruth",
                                     "--voxel", "0.05", "--threads", "1"};
    if (std::find(extra.begin(), extra.end(), "--segmenter") == extra.end()) extra.insert(extra.end(), {"--segmenter", "groundtruth"});
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  }
  inline static TempDir* tmp_ = nullptr;
};

}  // namespace semap::test
