#include "io/output_folder.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "semap/core/error.hpp"
#include "core/paths.hpp"

namespace semap {

namespace fs = std::filesystem;

namespace {

constexpr const char* kMarker = ".semap-output";
constexpr const char* kStagingPrefix = ".semap-staging-";
constexpr const char* kStagingMarker = ".semap-staging";
constexpr size_t kMaxManifestBytes = size_t{64} << 20;
constexpr int kMaxDepth = 32;

std::atomic<int> g_signal{0};
std::atomic<int> g_publishing{0};

std::string manifest_name(const std::string& tool) { return ".semap-manifest-" + tool + ".json"; }
std::string journal_name(const std::string& tool) { return ".semap-manifest-" + tool + ".pending.json"; }

std::string errno_text(int error) { return std::strerror(error); }

/// Closes a descriptor at scope exit.
struct Fd {
  int fd = -1;
  explicit Fd(int f = -1) : fd(f) {}
  Fd(Fd&& o) noexcept : fd(o.fd) { o.fd = -1; }
  Fd& operator=(Fd&& o) noexcept {
    std::swap(fd, o.fd);
    return *this;
  }
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

/// A relative path that stays inside its folder: no "..", ".", empty or absolute parts.
bool is_safe_relative(const std::string& p) {
  if (p.empty() || p.size() > 4096 || p.front() == '/') return false;
  for (unsigned char c : p)
    if (c < 0x20 || c == 0x7f) return false;
  for (const auto& part : fs::path(p))
    if (part.empty() || part == "." || part == ".." || part.string().size() > 255) return false;
  return fs::path(p).lexically_normal().string() == p;
}

/// Opens dir/relative_dir component by component with O_NOFOLLOW (creating the missing ones
/// when `created` is given and recording them there). A symlink on the way is an error.
/// Returns -1 (errno ENOENT) when a part is absent and nothing may be created.
Fd open_chain(int root_fd, const fs::path& relative_dir, const fs::path& shown_root, std::vector<std::string>* created,
              const std::string& created_prefix = "") {
  Fd current(::dup(root_fd));
  fs::path so_far;
  for (const auto& part : relative_dir) {
    if (part.empty() || part == ".") continue;
    so_far /= part;
    if (created) {
      if (::mkdirat(current.fd, part.c_str(), 0755) == 0) created->push_back(created_prefix + so_far.string());
      else if (errno != EEXIST) throw Error(shown_root / so_far, "cannot create folder: " + errno_text(errno));
    }
    Fd next(::openat(current.fd, part.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
    if (next.fd < 0) {
      const int error = errno;
      if (!created && error == ENOENT) return Fd(-1);
      if (error == ELOOP || error == ENOTDIR)
        throw Error(shown_root / so_far, "is a symlink or not a folder: refusing to write through it");
      throw Error(shown_root / so_far, "cannot open folder: " + errno_text(error));
    }
    current = std::move(next);
  }
  return current;
}

bool is_regular_at(int dir_fd, const char* name) {
  struct stat st {};
  return ::fstatat(dir_fd, name, &st, AT_SYMLINK_NOFOLLOW) == 0 && S_ISREG(st.st_mode);
}

/// Entry names of a folder (without . and ..), never following symlinks.
std::vector<std::pair<std::string, unsigned char>> list_at(int dir_fd) {
  std::vector<std::pair<std::string, unsigned char>> names;
  const int copy = ::dup(dir_fd);
  if (copy < 0) return names;
  DIR* d = ::fdopendir(copy);
  if (!d) {
    ::close(copy);
    return names;
  }
  ::rewinddir(d);
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name == "." || name == "..") continue;
    unsigned char type = e->d_type;
    if (type == DT_UNKNOWN) {
      struct stat st {};
      if (::fstatat(dir_fd, name.c_str(), &st, AT_SYMLINK_NOFOLLOW) == 0)
        type = S_ISDIR(st.st_mode) ? DT_DIR : S_ISREG(st.st_mode) ? DT_REG : S_ISLNK(st.st_mode) ? DT_LNK : DT_UNKNOWN;
    }
    names.emplace_back(name, type);
  }
  ::closedir(d);
  return names;
}

/// Removes parent/name and everything under it without following any symlink.
void remove_tree_at(int parent_fd, const std::string& name, int depth = 0) {
  if (depth > kMaxDepth) return;
  Fd dir(::openat(parent_fd, name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
  if (dir.fd < 0) {
    ::unlinkat(parent_fd, name.c_str(), 0);
    return;
  }
  for (const auto& [entry, type] : list_at(dir.fd)) {
    if (type == DT_DIR) remove_tree_at(dir.fd, entry, depth + 1);
    else ::unlinkat(dir.fd, entry.c_str(), 0);
  }
  ::unlinkat(parent_fd, name.c_str(), AT_REMOVEDIR);
}

/// Atomic write of `bytes` to dir_fd/name: exclusive temp name, then renameat.
void write_at(int dir_fd, const std::string& name, const std::string& bytes, const fs::path& shown) {
  uint64_t r = 0;
  (void)::getrandom(&r, sizeof r, 0);
  const std::string tmp = "." + name + ".semap-tmp-" + std::to_string(::getpid()) + "-" + std::to_string(r);
  Fd fd(::openat(dir_fd, tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644));
  if (fd.fd < 0) throw Error(shown, "cannot write: " + errno_text(errno));
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd.fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = errno;
      ::unlinkat(dir_fd, tmp.c_str(), 0);
      throw Error(shown, "write failed (disk full?): " + errno_text(error));
    }
    done += static_cast<size_t>(n);
  }
  if (::renameat(dir_fd, tmp.c_str(), dir_fd, name.c_str()) != 0) {
    const int error = errno;
    ::unlinkat(dir_fd, tmp.c_str(), 0);
    throw Error(shown, "cannot write: " + errno_text(error));
  }
}

std::optional<std::string> read_at(int dir_fd, const std::string& name) {
  Fd fd(::openat(dir_fd, name.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC));
  struct stat st {};
  if (fd.fd < 0 || ::fstat(fd.fd, &st) != 0 || !S_ISREG(st.st_mode) || static_cast<size_t>(st.st_size) > kMaxManifestBytes)
    return std::nullopt;
  std::string bytes(static_cast<size_t>(st.st_size), '\0');
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::read(fd.fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) return std::nullopt;
    done += static_cast<size_t>(n);
  }
  return bytes;
}

struct Manifest {
  std::set<std::string> files, dirs;
};

/// A manifest or journal of `tool`; entries that could leave the folder are dropped.
Manifest parse_manifest(const std::optional<std::string>& text) {
  Manifest m;
  if (!text) return m;
  try {
    const auto j = nlohmann::json::parse(*text);
    for (const char* key : {"files", "dirs"}) {
      if (!j.contains(key) || !j[key].is_array()) continue;
      for (const auto& entry : j[key])
        if (entry.is_string() && is_safe_relative(entry.get<std::string>()))
          (std::string(key) == "files" ? m.files : m.dirs).insert(entry.get<std::string>());
    }
  } catch (const nlohmann::json::exception&) {
    return {};  // unreadable: remove nothing
  }
  return m;
}

std::string manifest_text(const std::string& tool, const std::vector<std::string>& files, const std::set<std::string>& dirs,
                          bool complete) {
  nlohmann::json j;
  j["semap_manifest"] = 1;
  j["tool"] = tool;
  j["complete"] = complete;
  j["files"] = files;
  j["dirs"] = std::vector<std::string>(dirs.begin(), dirs.end());
  return j.dump(1) + "\n";
}

/// Regular files (relative paths) and folders under a staging folder.
void walk_staging(int dir_fd, const std::string& prefix, std::vector<std::string>& files, std::vector<std::string>& dirs,
                  int depth) {
  if (depth > kMaxDepth) throw Error(prefix, "staging folder nested too deeply");
  for (const auto& [name, type] : list_at(dir_fd)) {
    if (depth == 0 && name == kStagingMarker) continue;
    if (is_semap_temp_name(name)) continue;  // a writer's leftover
    const std::string rel = prefix.empty() ? name : prefix + "/" + name;
    if (type == DT_DIR) {
      Fd sub(::openat(dir_fd, name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
      if (sub.fd < 0) continue;
      dirs.push_back(rel);
      walk_staging(sub.fd, rel, files, dirs, depth + 1);
    } else if (type == DT_REG) {
      files.push_back(rel);
    }
  }
}

/// The folder holding dir/relative reached without symlinks, else -1 (never an error: what
/// cannot be reached safely is left alone).
Fd parent_of_listed(int dir_fd, const std::string& relative) {
  try {
    return open_chain(dir_fd, fs::path(relative).parent_path(), {}, nullptr);
  } catch (const Error&) {
    return Fd(-1);
  }
}

/// Unlinks dir/relative when it is a regular file reached without symlinks.
void remove_listed_file(int dir_fd, const std::string& relative) {
  const fs::path p(relative);
  Fd parent = parent_of_listed(dir_fd, relative);
  if (parent.fd < 0 || !is_regular_at(parent.fd, p.filename().c_str())) return;
  ::unlinkat(parent.fd, p.filename().c_str(), 0);
}

void remove_listed_dir_if_empty(int dir_fd, const std::string& relative) {
  Fd parent = parent_of_listed(dir_fd, relative);
  if (parent.fd >= 0) ::unlinkat(parent.fd, fs::path(relative).filename().c_str(), AT_REMOVEDIR);  // fails unless empty
}

bool process_alive(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH); }

long pid_in(const std::string& name, size_t start) {
  return start < name.size() ? std::strtol(name.c_str() + start, nullptr, 10) : 0;
}

/// Staging folders and temp files left by processes that no longer run.
void remove_dead_leftovers(int dir_fd) {
  const std::string staging_prefix = kStagingPrefix;
  for (const auto& [name, type] : list_at(dir_fd)) {
    if (type == DT_DIR && name.rfind(staging_prefix, 0) == 0) {
      const long pid = pid_in(name, staging_prefix.size());
      if (pid == ::getpid() || process_alive(pid)) continue;
      Fd sub(::openat(dir_fd, name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
      if (sub.fd >= 0 && is_regular_at(sub.fd, kStagingMarker)) remove_tree_at(dir_fd, name);
    } else if (type == DT_REG && is_semap_temp_name(name)) {
      const size_t at = name.rfind(".semap-tmp-");
      const long pid = pid_in(name, at + std::strlen(".semap-tmp-"));
      if (pid != ::getpid() && !process_alive(pid)) ::unlinkat(dir_fd, name.c_str(), 0);
    }
  }
}

std::string random_hex() {
  uint64_t r = 0;
  if (::getrandom(&r, sizeof r, 0) != static_cast<ssize_t>(sizeof r)) r = static_cast<uint64_t>(::time(nullptr)) ^ uint64_t(::getpid()) << 20;
  char buffer[24];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(r));
  return buffer;
}

/// Signals that arrive while publishing only set the flag (the process is not ended half-way).
struct PublishingScope {
  PublishingScope() { ++g_publishing; }
  ~PublishingScope() { --g_publishing; }
};

/// Absolute, with symlinks and ".." resolved as far as the path exists.
fs::path resolved(const fs::path& p) {
  std::error_code ec;
  const fs::path absolute = fs::absolute(p, ec);
  if (ec) return p.lexically_normal();
  const fs::path canonical = fs::weakly_canonical(absolute, ec);
  return ec ? absolute.lexically_normal() : canonical;
}

/// True when `inner` lies strictly inside `outer` (both resolved), compared part by part.
bool strictly_inside(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i) {
    if (o->empty()) continue;  // a trailing separator
    if (i == inner.end() || *i != *o) return false;
  }
  return i != inner.end() && !i->empty();
}

bool same_file(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  return fs::equivalent(a, b, ec) && !ec;
}

/// Issue 44: every output whose place in DIR already holds something this tool's manifest or
/// journal does not list (a user's mesh.ply) stops the publish before anything is moved.
void refuse_foreign_targets(int dir_fd, const std::vector<std::string>& files, const Manifest& owned, const fs::path& dir,
                            const std::string& manifest) {
  for (const auto& rel : files) {
    if (owned.files.count(rel)) continue;
    const fs::path p(rel);
    Fd parent = parent_of_listed(dir_fd, rel);
    struct stat st {};
    if (parent.fd < 0 || ::fstatat(parent.fd, p.filename().c_str(), &st, AT_SYMLINK_NOFOLLOW) != 0) continue;
    throw Error(dir / p, "exists and was not written by semap (not listed in " + manifest +
                             "): refusing to replace it; move it away or give another output folder");
  }
}

/// What `tool` wrote into DIR: its manifest, and the journal of a publish cut short.
Manifest owned_by_tool(int dir_fd, const std::string& tool) {
  Manifest owned = parse_manifest(read_at(dir_fd, manifest_name(tool)));
  const Manifest pending = parse_manifest(read_at(dir_fd, journal_name(tool)));
  owned.files.insert(pending.files.begin(), pending.files.end());
  owned.dirs.insert(pending.dirs.begin(), pending.dirs.end());
  return owned;
}

}  // namespace

// METHODS.md does not cover I/O; issue 44 class 4: an output folder never is or holds an input.
void refuse_output_over_inputs(const fs::path& out_dir, const std::vector<fs::path>& inputs) {
  const fs::path out = resolved(out_dir);
  for (const fs::path& input : inputs) {
    if (input.empty()) continue;
    const fs::path in = resolved(input);
    if (in == out || same_file(input, out_dir))
      throw Error(out_dir, "is the input " + input.string() +
                               " itself: refusing to write outputs into it; give another output folder");
    if (!strictly_inside(in, out)) continue;
    throw Error(out_dir, "contains the input " + input.string() +
                             ": refusing to write outputs over it; give a folder outside the inputs");
  }
}

// ------------------------------------------------------------------------------ OutputFolder

bool OutputFolder::is_internal_name(const std::string& name) {
  return name == kMarker || name.rfind(".semap-manifest-", 0) == 0 || name.rfind(kStagingPrefix, 0) == 0 ||
         is_semap_temp_name(name);
}

OutputFolder::OutputFolder(fs::path dir, OutputFolderOptions options) : dir_(std::move(dir)), options_(std::move(options)) {
  if (dir_.empty()) throw Error("--out", "no output folder given");
  const bool tool_ok = !options_.tool.empty() && std::all_of(options_.tool.begin(), options_.tool.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_';
  });
  if (!tool_ok) throw Error("OutputFolder", "tool name '" + options_.tool + "' must be letters, digits, - or _");
  refuse_output_over_inputs(dir_, options_.inputs);
  struct stat st {};
  if (::stat(dir_.c_str(), &st) != 0) {
    if (errno != ENOENT) throw Error(dir_, "output folder is " + describe_path(dir_));
    std::error_code ec;
    if (dir_.has_parent_path()) fs::create_directories(dir_.parent_path(), ec);
    if (ec) throw Error(dir_.parent_path(), "cannot create folder: " + ec.message());
    if (::mkdir(dir_.c_str(), 0755) == 0) created_dir_ = true;
    else if (errno != EEXIST) throw Error(dir_, "cannot create output folder: " + errno_text(errno));
  } else if (!S_ISDIR(st.st_mode)) {
    throw Error(dir_, "exists and is " + describe_path(dir_) + ", not a folder");
  }
  dir_fd_ = ::open(dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd_ < 0) throw Error(dir_, "cannot open output folder: " + errno_text(errno));
  try {
    if (::flock(dir_fd_, LOCK_EX | LOCK_NB) != 0)
      throw Error(dir_, "is being written by another semap command; wait until it finishes");
    remove_dead_leftovers(dir_fd_);
    refuse_foreign_targets(dir_fd_, options_.planned, owned_by_tool(dir_fd_, options_.tool), dir_,
                           manifest_name(options_.tool));
    const bool has_marker = is_regular_at(dir_fd_, kMarker);
    bool non_empty = false;
    for (const auto& [name, type] : list_at(dir_fd_)) non_empty = non_empty || !is_internal_name(name);
    if (!has_marker && non_empty && options_.refuse_foreign_non_empty)
      throw Error(dir_, "is not empty and was not made by semap (no " + std::string(kMarker) +
                            " marker): refusing to write into it; give a new or an empty folder");
    if (!has_marker && !non_empty) {
      write_at(dir_fd_, kMarker, "semap output folder: files listed in .semap-manifest-*.json were written by semap\n",
               dir_ / kMarker);
      wrote_marker_ = true;
    }
    std::string name;
    for (int attempt = 0; attempt < 16 && staging_.empty(); ++attempt) {
      name = kStagingPrefix + std::to_string(::getpid()) + "-" + random_hex();
      if (::mkdirat(dir_fd_, name.c_str(), 0755) == 0) staging_ = dir_ / name;
      else if (errno != EEXIST) throw Error(dir_, "cannot create a staging folder: " + errno_text(errno));
    }
    if (staging_.empty()) throw Error(dir_, "cannot create a unique staging folder");
    Fd staging_fd = open_chain(dir_fd_, name, dir_, nullptr);
    write_at(staging_fd.fd, kStagingMarker, "semap staging folder (removed when the command ends)\n", staging_);
  } catch (...) {
    abandon();
    ::close(dir_fd_);  // no destructor runs after a throwing constructor: release the lock here
    dir_fd_ = -1;
    throw;
  }
}

OutputFolder::~OutputFolder() {
  if (!done_) abandon();
  if (dir_fd_ >= 0) ::close(dir_fd_);
}

fs::path OutputFolder::path(const fs::path& relative) const {
  const std::string rel = relative.lexically_normal().string();
  if (!is_safe_relative(rel)) throw Error(relative, "output name must stay inside the output folder");
  if (relative.has_parent_path()) {
    Fd staging_fd = open_chain(dir_fd_, staging_.filename(), dir_, nullptr);
    std::vector<std::string> ignored;
    if (staging_fd.fd >= 0) open_chain(staging_fd.fd, fs::path(rel).parent_path(), staging_, &ignored);
  }
  return staging_ / rel;
}

void OutputFolder::abandon() noexcept {
  if (dir_fd_ < 0 || done_) return;
  done_ = true;
  if (!staging_.empty()) remove_tree_at(dir_fd_, staging_.filename().string());
  if (wrote_marker_) ::unlinkat(dir_fd_, kMarker, 0);
  if (created_dir_) ::rmdir(dir_.c_str());  // only when nothing else is in it
}

std::vector<std::string> OutputFolder::read_manifest(const fs::path& dir, const std::string& tool) {
  Fd fd(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (fd.fd < 0) return {};
  const Manifest m = parse_manifest(read_at(fd.fd, manifest_name(tool)));
  return {m.files.begin(), m.files.end()};
}

namespace {

/// Sorted, with `last` moved to the end in its order (the files that say "complete").
void order_for_publish(std::vector<std::string>& files, const std::vector<std::string>& last) {
  std::sort(files.begin(), files.end());
  for (const auto& name : last) {
    const auto it = std::find(files.begin(), files.end(), name);
    if (it == files.end()) continue;
    files.erase(it);
    files.push_back(name);
  }
}

/// Renames staging/rel to dir/rel for every file, creating (and recording) folders on the way.
void move_into_place(int dir_fd, int staging_fd, const std::vector<std::string>& files, const fs::path& dir,
                     const fs::path& staging, std::vector<std::string>& created_dirs) {
  for (const auto& rel : files) {
    const fs::path p(rel);
    Fd target = open_chain(dir_fd, p.parent_path(), dir, &created_dirs);
    Fd source = open_chain(staging_fd, p.parent_path(), staging, nullptr);
    if (source.fd < 0 || ::renameat(source.fd, p.filename().c_str(), target.fd, p.filename().c_str()) != 0) {
      const int error = errno;
      throw Error(dir / p, error == EISDIR || error == ENOTEMPTY ? "is a folder; cannot replace it with a file"
                                                                  : "cannot publish: " + errno_text(error));
    }
  }
}

/// The previous run's files and folders this run did not write: removed (remove_stale) or
/// kept and listed again. `manifest` holds this run's entries and receives the kept ones.
void settle_previous_run(int dir_fd, const Manifest& old, bool remove_stale, Manifest& manifest) {
  for (const auto& f : old.files) {
    if (manifest.files.count(f)) continue;
    if (remove_stale) {
      remove_listed_file(dir_fd, f);
      continue;
    }
    Fd parent = parent_of_listed(dir_fd, f);
    if (parent.fd >= 0 && is_regular_at(parent.fd, fs::path(f).filename().c_str())) manifest.files.insert(f);
  }
  std::vector<std::string> old_dirs(old.dirs.begin(), old.dirs.end());
  std::sort(old_dirs.begin(), old_dirs.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
  for (const auto& d : old_dirs) {  // deepest first
    if (manifest.dirs.count(d)) continue;
    if (remove_stale) remove_listed_dir_if_empty(dir_fd, d);
    else manifest.dirs.insert(d);
  }
}

}  // namespace

std::vector<std::string> OutputFolder::publish() {
  if (done_) throw Error(dir_, "output folder already published or abandoned");
  PublishingScope publishing;
  const std::string staging_name = staging_.filename().string();
  Fd staging_fd = open_chain(dir_fd_, staging_name, dir_, nullptr);
  if (staging_fd.fd < 0) throw Error(staging_, "staging folder vanished before publishing");
  std::vector<std::string> files, dirs;
  walk_staging(staging_fd.fd, "", files, dirs, 0);
  order_for_publish(files, options_.publish_last);
  const std::string manifest = manifest_name(options_.tool), journal = journal_name(options_.tool);
  const Manifest old = owned_by_tool(dir_fd_, options_.tool);
  refuse_foreign_targets(dir_fd_, files, old, dir_, manifest);
  // Every folder of the run first, empty ones too (objects/ of a map without objects): a
  // symlink planted in its place is refused before anything of the old run is touched.
  std::vector<std::string> created_dirs;
  for (const auto& d : dirs) open_chain(dir_fd_, d, dir_, &created_dirs);

  // Journal first: everything semap may own in DIR after this point, should we be cut short.
  Manifest everything = old;
  everything.files.insert(files.begin(), files.end());
  everything.dirs.insert(dirs.begin(), dirs.end());
  write_at(dir_fd_, journal, manifest_text(options_.tool, {everything.files.begin(), everything.files.end()},
                                           everything.dirs, false), dir_ / journal);
  ::unlinkat(dir_fd_, manifest.c_str(), 0);  // the folder no longer claims a complete run
  for (const auto& last : options_.publish_last)
    if (old.files.count(last)) remove_listed_file(dir_fd_, last);

  move_into_place(dir_fd_, staging_fd.fd, files, dir_, staging_, created_dirs);

  // Folders listed: the ones this publish created and the earlier ones still in use.
  Manifest now{{files.begin(), files.end()}, {created_dirs.begin(), created_dirs.end()}};
  for (const auto& d : dirs)
    if (old.dirs.count(d)) now.dirs.insert(d);
  settle_previous_run(dir_fd_, old, options_.remove_stale, now);
  write_at(dir_fd_, manifest, manifest_text(options_.tool, {now.files.begin(), now.files.end()}, now.dirs, true),
           dir_ / manifest);
  ::unlinkat(dir_fd_, journal.c_str(), 0);
  remove_tree_at(dir_fd_, staging_name);
  done_ = true;
  return files;
}

// ------------------------------------------------------------------------------ interruption

namespace {

std::mutex g_guard_mutex;
int g_guard_depth = 0;
struct sigaction g_old_int {}, g_old_term {};

extern "C" void on_interrupt(int signal_number) {
  int expected = 0;
  if (g_signal.compare_exchange_strong(expected, signal_number) || g_publishing.load() > 0) {
    static const char kLine[] = "\nsemap: stopping at the next safe point; press Ctrl-C again to quit at once\n";
    if (expected == 0) (void)!::write(STDERR_FILENO, kLine, sizeof kLine - 1);
    return;
  }
  paths_detail::unlink_registered_temps_from_signal_handler();
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

}  // namespace

InterruptGuard::InterruptGuard() {
  const std::lock_guard<std::mutex> lock(g_guard_mutex);
  if (g_guard_depth++ > 0) return;
  g_signal = 0;
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, &g_old_int);
  ::sigaction(SIGTERM, &action, &g_old_term);
}

InterruptGuard::~InterruptGuard() {
  const std::lock_guard<std::mutex> lock(g_guard_mutex);
  if (--g_guard_depth > 0) return;
  ::sigaction(SIGINT, &g_old_int, nullptr);
  ::sigaction(SIGTERM, &g_old_term, nullptr);
}

int interrupt_signal() { return g_signal.load(); }

void throw_if_interrupted() {
  if (const int s = g_signal.load()) throw Interrupted(s);
}

}  // namespace semap
