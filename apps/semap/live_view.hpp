#pragma once
// `semap run --view`: the growing map served to the browser viewer while it is built. A
// snapshot thread reads the Mapper's thread-safe accessors every refresh interval (mesh,
// trajectory, objects, stats) and encodes them once; the HTTP threads serve those bytes from
// memory (nothing is written to disk), next to the embedded viewer in live mode, which polls
// live.json and reloads what changed. The mapping loop never waits on the viewer: the only
// shared cost is the mesh extraction of a snapshot (changed blocks only).
#include <chrono>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "semap/mapper.hpp"

namespace semap::app {

class ViewerServer;  // apps/semap/viewer_server.hpp (cpp-httplib stays out of this header)

class LiveView {
 public:
  /// Binds host:port (throws semap::Error naming --port when it cannot) and starts serving.
  LiveView(const std::string& host, int port, std::chrono::milliseconds refresh, std::string title);
  ~LiveView();
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  /// RunOptions::observe_mapper. With a Mapper: snapshots start. With nullptr: one last
  /// snapshot of the finished map is taken, then the Mapper is never touched again (the
  /// destructor then serves it two more refresh intervals, for the page to load it).
  void observe(const Mapper* mapper);
  /// Snapshots taken so far.
  size_t snapshots() const;

 private:
  using Bytes = std::shared_ptr<const std::string>;
  void snapshot_loop();
  void take_snapshot(const Mapper& mapper);
  Bytes file(const std::string& name) const;
  void publish(std::map<std::string, Bytes> files);
  void add_routes();

  std::chrono::milliseconds refresh_;
  std::string title_;
  std::chrono::steady_clock::time_point started_;
  mutable std::mutex files_mutex_;
  std::map<std::string, Bytes> files_;  ///< URL path (without the leading '/') -> bytes
  std::mutex mapper_mutex_;             ///< held while a snapshot reads the Mapper
  const Mapper* mapper_ = nullptr;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool final_snapshot_ = false;
  size_t version_ = 0;
  std::unique_ptr<ViewerServer> server_;
  std::thread snapshot_thread_;
};

}  // namespace semap::app
