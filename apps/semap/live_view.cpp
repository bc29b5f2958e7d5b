#include "apps/semap/live_view.hpp"

#include <cstdio>
#include <nlohmann/json.hpp>

#include "semap/core/error.hpp"
#include "semap/core/gravity.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"
// After Eigen: cpp-httplib brings <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include "apps/semap/viewer_server.hpp"

#ifdef SEMAP_HAVE_VIEWER_ASSETS
#include "viewer/viewer_assets.hpp"
#endif

namespace semap::app {

namespace {

std::shared_ptr<const std::string> bytes(std::string text) {
  return std::make_shared<const std::string>(std::move(text));
}

/// viewer.json in live mode: the same files as an output folder, plus the state to poll.
std::string live_manifest(const std::string& title, std::chrono::milliseconds refresh) {
  const nlohmann::json manifest{
      {"title", title},
      {"files",
       {{"mesh", "../mesh.ply"}, {"objects", "../objects.json"}, {"trajectory", "../trajectory.txt"},
        {"classes", "classes.json"}}},
      {"live", {{"state", "../live.json"}, {"interval_ms", refresh.count()}}}};
  return manifest.dump(2) + "\n";
}

nlohmann::json live_state(const MapperStats& stats, const Trajectory& trajectory, size_t version, double elapsed_s) {
  nlohmann::json state{{"version", version},
                       {"frames", stats.frames},
                       {"frames_fused", stats.frames_fused},
                       {"keyframes", stats.keyframes},
                       {"lost_frames", stats.lost_frames},
                       {"objects", stats.objects},
                       {"finished", stats.finished},
                       {"fps", elapsed_s > 0 ? static_cast<double>(stats.frames) / elapsed_s : 0.0}};
  if (!trajectory.empty()) {
    const Eigen::Matrix4d T = trajectory.back().T_world_camera.matrix();
    std::vector<double> row_major;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) row_major.push_back(T(r, c));
    state["T_world_camera"] = row_major;
  }
  return state;
}

}  // namespace

LiveView::LiveView(const std::string& host, int port, std::chrono::milliseconds refresh, std::string title)
    : refresh_(refresh), title_(std::move(title)), started_(std::chrono::steady_clock::now()) {
#if defined(SEMAP_HAVE_HTTPLIB) && defined(SEMAP_HAVE_VIEWER_ASSETS)
  if (viewer::embedded_assets().empty())
    throw Error("--view", "the browser viewer was not built into this binary: " + std::string(viewer::unavailable_reason()));
  std::map<std::string, Bytes> files;
  for (const auto& asset : viewer::embedded_assets()) files["viewer/" + std::string(asset.name)] = bytes(std::string(asset.bytes));
  files["viewer/classes.json"] = bytes(classes_json());
  files["viewer/viewer.json"] = bytes(live_manifest(title_, refresh_));
  // An empty map until the first snapshot: the page never meets a missing file.
  files["mesh.ply"] = bytes(encode_ply(TriangleMesh(), "live mesh.ply"));
  files["trajectory.txt"] = bytes(format_tum_trajectory({}, "live trajectory.txt"));
  files["objects.json"] = bytes(objects_json({}).dump() + "\n");
  files["live.json"] = bytes(live_state(MapperStats(), {}, 0, 0.0).dump() + "\n");
  publish(std::move(files));
  server_ = std::make_unique<ViewerServer>(host, port);
  add_routes();
  server_->start();
  server_->print_urls("semap run: live view of the map while it is built");
  snapshot_thread_ = std::thread([this] { snapshot_loop(); });
#else
  (void)host;
  (void)port;
  throw Error("--view", "this binary was built without the browser viewer or cpp-httplib");
#endif
}

LiveView::~LiveView() {
  bool showed_final_map;
  {
    std::lock_guard lock(mapper_mutex_);
    stopping_ = true;
    showed_final_map = final_snapshot_;
  }
  // The page polls every refresh: leave it time to load the finished map before closing.
  if (showed_final_map) std::this_thread::sleep_for(2 * refresh_);
  wake_.notify_all();
  if (snapshot_thread_.joinable()) snapshot_thread_.join();
#ifdef SEMAP_HAVE_HTTPLIB
  if (server_) server_->stop();
#endif
  server_.reset();
}

void LiveView::observe(const Mapper* mapper) {
  std::lock_guard lock(mapper_mutex_);  // waits for a snapshot in progress
  if (!mapper && mapper_) {
    try {
      take_snapshot(*mapper_);  // the finished map
      final_snapshot_ = true;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "semap run: live view: %s\n", e.what());
    }
  }
  mapper_ = mapper;
  wake_.notify_all();
}

size_t LiveView::snapshots() const {
  std::lock_guard lock(files_mutex_);
  return version_;
}

void LiveView::snapshot_loop() {
  std::unique_lock lock(mapper_mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, refresh_, [&] { return stopping_; });
    if (stopping_ || !mapper_) continue;
    try {
      take_snapshot(*mapper_);
    } catch (const std::exception& e) {  // the next snapshot tries again; mapping goes on
      std::fprintf(stderr, "semap run: live view: %s\n", e.what());
    }
  }
}

void LiveView::take_snapshot(const Mapper& mapper) {
  const Trajectory trajectory = mapper.trajectory();
  const MapperStats stats = mapper.stats();
  std::map<std::string, Bytes> files;
  const TriangleMesh mesh = mapper.mesh();
  files["mesh.ply"] = bytes(encode_ply(mesh, "live mesh.ply"));
  files["trajectory.txt"] = bytes(format_tum_trajectory(trajectory, "live trajectory.txt"));
  files["objects.json"] = bytes(objects_json(mapper.objects()).dump() + "\n");
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  size_t version;
  {
    std::lock_guard lock(files_mutex_);
    version = version_ + 1;
  }
  nlohmann::json state = live_state(stats, trajectory, version, elapsed_s);
  // Issue 43: the up the report and `semap view` use (core/gravity), not the page's own guess.
  const Eigen::Vector3d up = estimate_gravity(mesh, trajectory).up_W;
  state["up"] = {up.x(), up.y(), up.z()};
  files["live.json"] = bytes(state.dump() + "\n");
  publish(std::move(files));
}

LiveView::Bytes LiveView::file(const std::string& name) const {
  std::lock_guard lock(files_mutex_);
  const auto it = files_.find(name);
  return it == files_.end() ? nullptr : it->second;
}

void LiveView::publish(std::map<std::string, Bytes> files) {
  std::lock_guard lock(files_mutex_);
  const bool snapshot = files.count("live.json") > 0 && !files_.empty();
  for (auto& [name, content] : files) files_[name] = std::move(content);
  if (snapshot) ++version_;
}

void LiveView::add_routes() {
#ifdef SEMAP_HAVE_HTTPLIB
  server_->http().Get("/.*", [this](const httplib::Request& req, httplib::Response& res) {
    // As in serve_file: no byte ranges (cpp-httplib 0.11 would apply any number of them).
    const_cast<httplib::Request&>(req).ranges.clear();
    const Bytes content = file(req.path.substr(1));
    if (!content) {
      res.status = 404;
      res.set_content("not found\n", "text/plain");
      return;
    }
    res.set_content(*content, mime_type(req.path));  // a copy: a snapshot may replace it meanwhile
  });
#endif
}

}  // namespace semap::app
