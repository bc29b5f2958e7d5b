#pragma once
// The viewer's local HTTP server (cpp-httplib), shared by `semap view DIR` (the files of an
// output folder) and `semap run --view` (the growing map, served from memory). Hardened as
// issue 22 asks: only regular files whose real path is inside the served folder, at most one
// byte range per request, idle connections dropped after 2 s, no-store caching, GET only.
// Issue 44 (class 6): a request must arrive whole within 5 s (not only byte by byte), a response
// must be taken at 64 KiB/s on average after 5 s (not only send by send), clients still sending their
// request hold at most half the threads, and stopping cuts every connection instead of waiting
// for slow clients.
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#ifdef SEMAP_HAVE_HTTPLIB
#include <httplib.h>
#endif

namespace semap::app {

/// classes.json: id, name, colour and stuff flag of every project class (core/labels).
std::string classes_json();
/// The MIME type of a served file by its extension.
std::string mime_type(const std::filesystem::path& file);

#ifdef SEMAP_HAVE_HTTPLIB
/// Answers GET/HEAD of a file inside `root_real` (canonical), streaming it; 404 for anything
/// outside, hidden (.semap*) or not a regular file; 416 for multi-range requests.
void serve_file(const std::filesystem::path& root_real, const httplib::Request& req, httplib::Response& res);

class ConnectionGuard;

/// An httplib server bound to host:port with the settings above. Routes are added through
/// http() before run()/start().
class ViewerServer {
 public:
  /// Binds (port 0: any free port). Throws semap::Error naming --host / --port when it cannot.
  ViewerServer(const std::string& host, int port);
  ~ViewerServer();
  ViewerServer(const ViewerServer&) = delete;
  ViewerServer& operator=(const ViewerServer&) = delete;

  httplib::Server& http();
  int port() const { return port_; }
  /// Prints the URL to open (and a warning when the address is reachable from other machines).
  void print_urls(const std::string& what) const;
  /// Serves on the calling thread until SIGINT/SIGTERM (the caller holds an InterruptGuard).
  void run_until_interrupted();
  /// Serves on a thread of its own until stop() or destruction.
  void start();
  /// Stops listening and cuts every open connection (a slow client is not waited for).
  void stop();

 private:
  std::unique_ptr<ConnectionGuard> guard_;
  std::unique_ptr<httplib::Server> server_;
  std::string host_;
  int port_ = 0;
  std::thread thread_;
};
#else
class ViewerServer {};  // built without cpp-httplib: never constructed
#endif

}  // namespace semap::app
