// `semap view DIR`: writes the browser viewer (embedded index.html + viewer.js, classes.json
// from core/labels, viewer.json listing the files present) into DIR/viewer/ and serves DIR on
// 127.0.0.1 until Ctrl-C (apps/semap/viewer_server: the hardened file server of issue 22).
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
#include "apps/semap/viewer_server.hpp"
#include "semap/core/error.hpp"
#include "semap/core/labels.hpp"
#include "core/paths.hpp"
#include "io/output_folder.hpp"

#ifdef SEMAP_HAVE_VIEWER_ASSETS
#include "viewer/viewer_assets.hpp"
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
  optional("grid", "map.pgm");  // issue 39: occupancy grid and scene graph layers
  optional("grid_yaml", "map.yaml");
  optional("scene_graph", "scene_graph.json");
  files["classes"] = "classes.json";
  const fs::path absolute = fs::weakly_canonical(dir);
  nlohmann::json manifest{{"title", absolute.filename().string()}, {"files", files}};
  // Issue 43: "up" as the run estimated it (report.json gravity.up, core/gravity), the same
  // estimate the live view gets; without it the page guesses from the mesh and trajectory.
  if (fs::is_regular_file(dir / "report.json")) {
    std::string text;
    try {
      text = read_regular_file(dir / "report.json", uint64_t{64} << 20, "report");
    } catch (const Error&) {  // unreadable or huge: the page estimates up itself
    }
    const auto report = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
    if (report.is_object() && report.contains("gravity") && report["gravity"].is_object() &&
        report["gravity"].contains("up") && report["gravity"]["up"].is_array() && report["gravity"]["up"].size() == 3)
      manifest["up"] = report["gravity"]["up"];
  }
  return manifest.dump(2) + "\n";
}

/// Writes DIR/viewer/{index.html, viewer.js, classes.json, viewer.json}; returns that folder.
/// Staged and published through io/output_folder: a `viewer` symlink planted in DIR is
/// refused, never written through.
fs::path write_viewer(const fs::path& dir) {
  if (!fs::is_directory(dir))
    throw Error(dir, "is " + describe_path(dir) + ", expected the output folder of `semap run` (holding mesh.ply)");
  if (!is_regular_file_path(dir / "mesh.ply")) {
    throw Error(dir / "mesh.ply", "missing: not a semap output folder (run `semap run` or `semap demo` first)");
  }
#ifdef SEMAP_HAVE_VIEWER_ASSETS
  const auto assets = viewer::embedded_assets();
  if (assets.empty()) {
    throw Error("semap view", "the browser viewer was not built into this binary: " +
                                  std::string(viewer::unavailable_reason()));
  }
  OutputFolder out(dir, {.tool = "view", .refuse_foreign_non_empty = false, .remove_stale = true, .publish_last = {}, .inputs = {}});
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

int serve(const fs::path& dir, const ViewOptions& options) {
#ifdef SEMAP_HAVE_HTTPLIB
  ViewerServer server(options.host, options.port);
  const fs::path root_real = fs::canonical(dir);
  server.http().Get("/.*", [root_real](const httplib::Request& req, httplib::Response& res) {
    serve_file(root_real, req, res);
  });
  const InterruptGuard interrupts;
  server.print_urls("semap view: serving " + dir.string());
  server.run_until_interrupted();
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
