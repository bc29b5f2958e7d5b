// `semap view DIR`: writes the browser viewer (embedded index.html + viewer.js, classes.json
// from core/labels, viewer.json listing the files present) into DIR/viewer/ and serves DIR on
// 127.0.0.1 with cpp-httplib until Ctrl-C.
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include "apps/semap/commands.hpp"
#include "semap/core/error.hpp"
#include "semap/core/labels.hpp"
#include "core/paths.hpp"

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
fs::path write_viewer(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw Error(dir, "no such output folder");
  if (!fs::is_regular_file(dir / "mesh.ply")) {
    throw Error(dir / "mesh.ply", "missing: not a semap output folder (run `semap run` or `semap demo` first)");
  }
#ifdef SEMAP_HAVE_VIEWER_ASSETS
  const auto assets = viewer::embedded_assets();
  if (assets.empty()) {
    throw Error("semap view", "the browser viewer was not built into this binary: " +
                                  std::string(viewer::unavailable_reason()));
  }
  const fs::path out = dir / "viewer";
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw Error(out, "cannot create folder: " + ec.message());
  for (const auto& asset : assets) write_file_atomic(out / std::string(asset.name), std::string(asset.bytes));
  write_file_atomic(out / "classes.json", classes_json());
  write_file_atomic(out / "viewer.json", manifest_json(dir));
  return out;
#else
  throw Error("semap view", "the browser viewer was not built into this binary (viewer/ not configured)");
#endif
}

std::atomic<bool> g_stop_requested{false};
extern "C" void request_stop(int) { g_stop_requested = true; }

int serve(const fs::path& dir, const ViewOptions& options) {
#ifdef SEMAP_HAVE_HTTPLIB
  httplib::Server server;
  server.set_file_extension_and_mimetype_mapping("ply", "application/octet-stream");
  server.set_file_extension_and_mimetype_mapping("txt", "text/plain; charset=utf-8");
  server.set_file_extension_and_mimetype_mapping("json", "application/json");
  if (!server.set_mount_point("/", dir.string())) throw Error(dir, "cannot serve this folder");
  // Outputs change between runs: never let the browser show a stale mesh.
  server.set_post_routing_handler([](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
  });
  server.Get("/", [](const httplib::Request&, httplib::Response& res) { res.set_redirect("/viewer/index.html"); });

  int port = options.port;
  if (port == 0) {
    port = server.bind_to_any_port(options.host);
    if (port <= 0) throw Error("--host", "cannot listen on " + options.host);
  } else if (!server.bind_to_port(options.host, port)) {
    throw Error("--port", "cannot listen on " + options.host + ":" + std::to_string(port) + " (in use?)");
  }

  g_stop_requested = false;
  struct sigaction action {};
  action.sa_handler = request_stop;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  // The signal handler only sets a flag; this thread turns it into server.stop().
  std::atomic<bool> listening_done{false};
  std::thread watcher([&] {
    while (!g_stop_requested && !listening_done) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    server.stop();
  });

  const std::string host_for_url = options.host == "0.0.0.0" ? "127.0.0.1" : options.host;
  std::printf("semap view: serving %s\n  open http://%s:%d/viewer/index.html   (Ctrl-C stops)\n",
              dir.string().c_str(), host_for_url.c_str(), port);
  std::fflush(stdout);
  const bool ok = server.listen_after_bind();
  listening_done = true;
  watcher.join();
  if (!ok && !g_stop_requested) throw Error("semap view", "the server stopped unexpectedly");
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
