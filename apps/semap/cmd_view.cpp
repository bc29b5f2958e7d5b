// `semap view DIR`: writes the browser viewer (embedded index.html + viewer.js, classes.json
// from core/labels, viewer.json listing the files present) into DIR/viewer/ and serves DIR on
// 127.0.0.1 with cpp-httplib until Ctrl-C: only regular files whose real path is inside DIR,
// at most one byte range per request, idle connections dropped after 2 s (issue 22).
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "apps/semap/commands.hpp"
#include "semap/core/error.hpp"
#include "semap/core/labels.hpp"
#include "core/paths.hpp"
#include "io/output_folder.hpp"

#ifdef SEMAP_HAVE_VIEWER_ASSETS
#include "viewer/viewer_assets.hpp"
#endif
#ifdef SEMAP_HAVE_HTTPLIB
#include <httplib.h>
#endif

namespace semap::app {
namespace {

namespace fs = std::filesystem;

struct ViewOptions {
  std::string dir;
  int port = 8765;
  std::string host = "127.0.0.1";
  bool no_serve = false;
};

// One source of truth for class names and colours: core/labels.
std::string classes_json() {
  nlohmann::json classes = nlohmann::json::array();
  for (int c = 0; c < kNumClasses; ++c) {
    const auto id = static_cast<ClassId>(c);
    const Rgb8 colour = class_colour(id);
    classes.push_back({{"id", c}, {"name", std::string(class_name(id))},
                       {"colour", {colour.r, colour.g, colour.b}}, {"stuff", is_stuff(id)}});
  }
  return classes.dump() + "\n";
}

// The page only fetches files listed here, so absent optional files cause no 404s.
std::string manifest_json(const fs::path& dir) {
  nlohmann::json files;
  const auto optional = [&](const char* key, const char* name) {
    files[key] = fs::is_regular_file(dir / name) ? nlohmann::json("../" + std::string(name)) : nlohmann::json(nullptr);
  };
  optional("mesh", "mesh.ply");
  optional("objects", "objects.json");
  optional("trajectory", "trajectory.txt");
  optional("report", "report.html");
  files["classes"] = "classes.json";
  const fs::path absolute = fs::weakly_canonical(dir);
  nlohmann::json manifest{{"title", absolute.filename().string()}, {"files", files}};
  return manifest.dump(2) + "\n";
}

/// Writes DIR/viewer/{index.html, viewer.js, classes.json, viewer.json}; returns that folder.
/// Staged and published through io/output_folder: a `viewer` symlink planted in DIR is
/// refused, never written through.
fs::path write_viewer(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw Error(dir, "output folder is " + describe_path(dir));
  if (!is_regular_file_path(dir / "mesh.ply")) {
    throw Error(dir / "mesh.ply", "missing: not a semap output folder (run `semap run` or `semap demo` first)");
  }
#ifdef SEMAP_HAVE_VIEWER_ASSETS
  const auto assets = viewer::embedded_assets();
  if (assets.empty()) {
    throw Error("semap view", "the browser viewer was not built into this binary: " +
                                  std::string(viewer::unavailable_reason()));
  }
  OutputFolder out(dir, {.tool = "view", .refuse_foreign_non_empty = false, .remove_stale = true, .publish_last = {}});
  for (const auto& asset : assets)
    write_file_atomic(out.path(fs::path("viewer") / std::string(asset.name)), std::string(asset.bytes));
  write_file_atomic(out.path("viewer/classes.json"), classes_json());
  write_file_atomic(out.path("viewer/viewer.json"), manifest_json(dir));
  out.publish();
  return dir / "viewer";
#else
  throw Error("semap view", "the browser viewer was not built into this binary (viewer/ not configured)");
#endif
}

#ifdef SEMAP_HAVE_HTTPLIB
// ------------------------------------------------------------------ the file server (issue 22)

constexpr size_t kServerThreads = 32;         // idle keep-alive connections hold one each
constexpr time_t kReadTimeoutS = 2;           // an idle connection is dropped after this
constexpr size_t kKeepAliveMaxRequests = 100;

std::string mime_type(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js") return "text/javascript; charset=utf-8";
  if (ext == ".json") return "application/json";
  if (ext == ".txt") return "text/plain; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".png") return "image/png";
  return "application/octet-stream";  // .ply and the rest
}

/// The regular file a URL path names, when its real path (symlinks resolved) lies inside
/// `root_real`; nullopt otherwise (served as 404). semap's own bookkeeping files are hidden.
std::optional<fs::path> file_inside(const fs::path& root_real, const std::string& url_path) {
  if (url_path.find('\0') != std::string::npos) return std::nullopt;
  const fs::path relative = fs::path(url_path).relative_path();
  for (const auto& part : relative)
    if (part == ".." || part.string().rfind(".semap", 0) == 0) return std::nullopt;
  std::error_code ec;
  const fs::path real = fs::canonical(root_real / relative, ec);
  if (ec) return std::nullopt;
  const fs::path inside = real.lexically_relative(root_real);
  if (inside.empty() || *inside.begin() == ".." || inside.is_absolute()) return std::nullopt;
  if (!is_regular_file_path(real)) return std::nullopt;
  return real;
}

/// One byte range "bytes=a-b" | "a-" | "-n" of a file of `size` bytes, as [first, last].
/// Several ranges (the 1.25 GB response of 200 overlapping ones) are refused.
std::optional<std::pair<uint64_t, uint64_t>> parse_single_range(const std::string& header, uint64_t size) {
  if (header.rfind("bytes=", 0) != 0 || header.find(',') != std::string::npos || size == 0) return std::nullopt;
  const std::string spec = header.substr(6);
  const size_t dash = spec.find('-');
  if (dash == std::string::npos) return std::nullopt;
  const auto number = [](const std::string& text) -> std::optional<uint64_t> {
    if (text.empty() || text.size() > 19 || text.find_first_not_of("0123456789") != std::string::npos) return std::nullopt;
    return std::stoull(text);
  };
  const auto a = number(spec.substr(0, dash)), b = number(spec.substr(dash + 1));
  if (!a && b) {  // the last *b bytes
    if (*b == 0) return std::nullopt;
    return std::pair{size - std::min(*b, size), size - 1};
  }
  if (!a || *a >= size || (b && *b < *a)) return std::nullopt;
  return std::pair{*a, b ? std::min(*b, size - 1) : size - 1};
}

/// Answers GET/HEAD of a file inside the folder, streaming it (never loading it whole).
void serve_file(const fs::path& root_real, const httplib::Request& req, httplib::Response& res) {
  // cpp-httplib 0.11 would apply the request's ranges to our response again, with multipart
  // bodies for any number of them and no bounds checks: ranges are answered here only. The
  // Request is a non-const local of the server, so clearing them is well defined.
  const_cast<httplib::Request&>(req).ranges.clear();
  const auto file = file_inside(root_real, req.path);
  if (!file) {
    res.status = 404;
    res.set_content("not found\n", "text/plain");
    return;
  }
  auto fd = std::make_shared<int>(::open(file->c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC));
  struct stat st {};
  if (*fd < 0 || ::fstat(*fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    if (*fd >= 0) ::close(*fd);
    res.status = 404;
    res.set_content("not found\n", "text/plain");
    return;
  }
  const auto size = static_cast<uint64_t>(st.st_size);
  uint64_t first = 0, length = size;
  res.set_header("Accept-Ranges", "bytes");
  if (req.has_header("Range")) {
    const auto range = parse_single_range(req.get_header_value("Range"), size);
    if (!range) {
      ::close(*fd);
      res.status = 416;
      res.set_header("Content-Range", "bytes */" + std::to_string(size));
      return;
    }
    first = range->first;
    length = range->second - range->first + 1;
    res.status = 206;
    res.set_header("Content-Range", "bytes " + std::to_string(range->first) + "-" + std::to_string(range->second) + "/" +
                                        std::to_string(size));
  }
  res.set_content_provider(
      length, mime_type(*file),
      [fd, first](size_t offset, size_t count, httplib::DataSink& sink) {
        char buffer[1 << 16];
        const ssize_t n = ::pread(*fd, buffer, std::min(count, sizeof buffer), static_cast<off_t>(first + offset));
        if (n <= 0) return false;
        sink.write(buffer, static_cast<size_t>(n));
        return true;
      },
      [fd](bool) { ::close(*fd); });
}

bool is_loopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

std::string url_host(const std::string& host) {
  return host.find(':') != std::string::npos ? "[" + host + "]" : host;  // IPv6 literal
}

void print_urls(const fs::path& dir, const std::string& host, int port) {
  std::printf("semap view: serving %s\n", dir.string().c_str());
  if (host == "0.0.0.0" || host == "::" || host.empty()) {
    char name[256] = {0};
    ::gethostname(name, sizeof name - 1);
    std::fprintf(stderr,
                 "semap view: warning: --host %s listens on every network interface: anyone who can reach this "
                 "machine on port %d can read %s\n",
                 host.c_str(), port, dir.string().c_str());
    std::printf("  open http://127.0.0.1:%d/viewer/index.html on this machine, or http://%s:%d/viewer/index.html from "
                "another one   (Ctrl-C stops)\n",
                port, name, port);
  } else {
    if (!is_loopback(host))
      std::fprintf(stderr, "semap view: warning: --host %s is reachable from other machines: they can read %s\n",
                   host.c_str(), dir.string().c_str());
    std::printf("  open http://%s:%d/viewer/index.html   (Ctrl-C stops)\n", url_host(host).c_str(), port);
  }
  std::fflush(stdout);
}
#endif

int serve(const fs::path& dir, const ViewOptions& options) {
#ifdef SEMAP_HAVE_HTTPLIB
  const fs::path root_real = fs::canonical(dir);
  httplib::Server server;
  server.new_task_queue = [] { return new httplib::ThreadPool(kServerThreads); };
  server.set_read_timeout(kReadTimeoutS, 0);
  server.set_write_timeout(10, 0);
  server.set_keep_alive_timeout(kReadTimeoutS);
  server.set_keep_alive_max_count(kKeepAliveMaxRequests);
  server.set_payload_max_length(1 << 16);  // GET only: no request body worth reading
  // Outputs change between runs: never let the browser show a stale mesh.
  server.set_post_routing_handler([](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
  });
  server.Get("/", [](const httplib::Request&, httplib::Response& res) { res.set_redirect("/viewer/index.html"); });
  server.Get("/.*", [root_real](const httplib::Request& req, httplib::Response& res) { serve_file(root_real, req, res); });

  int port = options.port;
  if (port == 0) {
    port = server.bind_to_any_port(options.host);
    if (port <= 0) throw Error("--host", "cannot listen on " + options.host);
  } else if (!server.bind_to_port(options.host, port)) {
    throw Error("--port", "cannot listen on " + options.host + ":" + std::to_string(port) + " (in use?)");
  }

  // Ctrl-C / SIGTERM only set a flag (io/output_folder); this thread turns it into stop().
  const InterruptGuard interrupts;
  std::atomic<bool> listening_done{false};
  std::thread watcher([&] {
    while (interrupt_signal() == 0 && !listening_done) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    server.stop();
  });
  print_urls(dir, options.host, port);
  const bool ok = server.listen_after_bind();
  listening_done = true;
  watcher.join();
  if (!ok && interrupt_signal() == 0) throw Error("semap view", "the server stopped unexpectedly");
  std::printf("semap view: stopped\n");
  return 0;
#else
  (void)dir;
  (void)options;
  throw Error("semap view", "built without cpp-httplib (libcpp-httplib-dev): use --no-serve and open the page via a web server");
#endif
}

}  // namespace

void add_view_command(CLI::App& app, CommandRunner& run) {
  auto options = std::make_shared<ViewOptions>();
  auto* cmd = app.add_subcommand("view", "Open an output folder in the browser viewer (labelled mesh, objects, trajectory)");
  cmd->add_option("dir", options->dir, "output folder of `semap run` / `semap demo` (holds mesh.ply)")->required();
  cmd->add_option("--port", options->port, "TCP port to serve on (0: any free port)")->check(CLI::Range(0, 65535))->capture_default_str();
  cmd->add_option("--host", options->host, "address to listen on")->capture_default_str();
  cmd->add_flag("--no-serve", options->no_serve, "only write the page into DIR/viewer/, do not serve");
  cmd->callback([&run, options] {
    run = [options]() -> int {
      const fs::path dir = options->dir;
      const fs::path page = write_viewer(dir);
      if (options->no_serve) {
        std::printf("semap view: wrote %s (serve %s with any web server and open viewer/index.html)\n",
                    (page / "index.html").string().c_str(), dir.string().c_str());
        return 0;
      }
      return serve(dir, *options);
    };
  });
}

}  // namespace semap::app
