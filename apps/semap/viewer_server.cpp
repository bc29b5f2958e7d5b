#include "apps/semap/viewer_server.hpp"

#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>

#include <algorithm>
#include <charconv>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <map>
#include <mutex>
#include <tuple>
#include <vector>
#include <nlohmann/json.hpp>
#include <optional>

#include "apps/semap/tcp_progress.hpp"
#include "core/paths.hpp"
#include "io/output_folder.hpp"
#include "semap/core/error.hpp"
#include "semap/core/labels.hpp"

namespace semap::app {

namespace fs = std::filesystem;

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

#ifdef SEMAP_HAVE_HTTPLIB
namespace {

constexpr size_t kServerThreads = 32;         // idle keep-alive connections hold one each
constexpr time_t kReadTimeoutS = 2;           // an idle connection is dropped after this
constexpr size_t kKeepAliveMaxRequests = 100;
// Issue 44, class 6: a client sending one header line per second never hit the idle timeout.
constexpr auto kRequestReadLimit = std::chrono::seconds(5);     // a whole request arrives within this
constexpr size_t kMaxReadingConnections = kServerThreads / 2;   // the rest serve requests that arrived
constexpr auto kWatchdogPeriod = std::chrono::milliseconds(100);
// Issue 44 (third round): a client that reads its response a few bytes at a time kept a thread
// for ever (the write timeout bounds each send, not the response). After kResponseGrace, a
// response whose peer has taken less than kMinResponseBytesPerS on average since it began is
// cut: a response of B bytes takes at most max(5 s, B / 64 KiB/s).
constexpr auto kResponseGrace = std::chrono::seconds(5);
constexpr double kMinResponseBytesPerS = 64 * 1024;


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

bool is_loopback(const std::string& host) {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

std::string url_host(const std::string& host) {
  return host.find(':') != std::string::npos ? "[" + host + "]" : host;  // IPv6 literal
}

}  // namespace

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


/// "address:port" of a socket's peer (numeric, as httplib's Request::remote_addr/remote_port).
static std::string peer_key(const std::string& address, int port) { return address + "|" + std::to_string(port); }

/// The open connections of one server by phase: reading a request (since when) or answering
/// one (since when, and how much of it the peer has taken). A watchdog thread finds the server's connected sockets (the process's
/// sockets bound to its port; httplib 0.11 keeps them private) and cuts them with shutdown(2),
/// which wakes the worker blocked on one: a request not complete after kRequestReadLimit, a
/// response the peer takes too slowly (check_response_rate), the oldest reading ones beyond kMaxReadingConnections,
/// and on stop_all() every one. Thread-safe.
/// Listing /proc/self/fd races with the workers, which close their sockets at any time: a
/// number listed may be closed and reused (by a new connection, a served file, another
/// thread's socket) before it is cut. cut() therefore never acts on the listed number itself:
/// it duplicates it, checks that the duplicate is still a connection of this port from the same
/// peer, and shuts that down (a duplicate cannot be reused while held; shutdown acts on the
/// connection, not the number). A socket opened or closed during a listing is merely seen one
/// period (kWatchdogPeriod) later or not at all, which changes no decision.
class ConnectionGuard {
 public:
  using Clock = std::chrono::steady_clock;
  ConnectionGuard() = default;
  ~ConnectionGuard() {
    {
      std::lock_guard lock(mutex_);
      quit_ = true;
    }
    wake_.notify_all();
    if (watchdog_.joinable()) watchdog_.join();
  }
  ConnectionGuard(const ConnectionGuard&) = delete;
  ConnectionGuard& operator=(const ConnectionGuard&) = delete;

  /// Starts watching the connections to `port`.
  void watch_port(int port) {
    port_ = port;
    watchdog_ = std::thread([this] { watch(); });
  }
  /// A request of this peer has arrived whole (the handler runs; answering() follows).
  void request_read(const std::string& address, int port) { set_reading(peer_key(address, port), false); }
  /// The response starts going out: from now on the peer must take it at kMinResponseBytesPerS.
  void answering(const std::string& address, int port) {
    std::lock_guard lock(mutex_);
    Connection& c = connections_[peer_key(address, port)];
    c.answering_since = Clock::now();
    c.acked_at_answer.reset();
  }
  /// The response went out: the peer's next request (keep-alive) starts now.
  void response_sent(const std::string& address, int port) { set_reading(peer_key(address, port), true); }
  /// Cuts every connection, now and every one found later.
  void stop_all() {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    for (const auto& [fd, key] : scan()) cut(fd, key);
  }

 private:
  struct Connection {
    Clock::time_point reading_since = Clock::now();
    std::optional<Clock::time_point> answering_since;  ///< set while a response goes out
    std::optional<uint64_t> acked_at_answer;            ///< tcp_bytes_acked when first seen answering
    bool reading = true;
    bool seen = false;
  };

  void set_reading(const std::string& key, bool reading) {
    std::lock_guard lock(mutex_);
    Connection& c = connections_[key];
    c.reading = reading;
    c.reading_since = Clock::now();
    c.answering_since.reset();
  }
  /// The peer key of `fd` when it is a socket connected through the server's port.
  std::optional<std::string> server_peer_of(int fd) const {
    sockaddr_storage local{}, peer{};
    socklen_t local_size = sizeof local, peer_size = sizeof peer;
    if (::getsockname(fd, reinterpret_cast<sockaddr*>(&local), &local_size) != 0) return std::nullopt;
    if (local.ss_family != AF_INET && local.ss_family != AF_INET6) return std::nullopt;
    const int local_port = ntohs(local.ss_family == AF_INET ? reinterpret_cast<sockaddr_in&>(local).sin_port
                                                           : reinterpret_cast<sockaddr_in6&>(local).sin6_port);
    if (local_port != port_ || ::getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &peer_size) != 0) return std::nullopt;
    char host[NI_MAXHOST], service[NI_MAXSERV];
    if (::getnameinfo(reinterpret_cast<sockaddr*>(&peer), peer_size, host, sizeof host, service, sizeof service,
                      NI_NUMERICHOST | NI_NUMERICSERV) != 0)
      return std::nullopt;
    return peer_key(host, std::atoi(service));
  }
  /// The process's sockets connected through the server's port: fd -> peer key (a snapshot:
  /// act on one only through cut()).
  std::vector<std::pair<int, std::string>> scan() const {
    std::vector<std::pair<int, std::string>> out;
    std::error_code ec;
    for (fs::directory_iterator it("/proc/self/fd", ec), end; !ec && it != end; it.increment(ec)) {
      int fd = -1;
      const std::string name = it->path().filename().string();
      if (std::from_chars(name.data(), name.data() + name.size(), fd).ec != std::errc()) continue;
      if (auto key = server_peer_of(fd)) out.emplace_back(fd, std::move(*key));
    }
    return out;
  }
  /// Runs act(held) on a duplicate of `fd` when it is still the connection `key` that scan()
  /// listed, not a number since closed or reused (see the class comment).
  template <class Act>
  void on_connection(int fd, const std::string& key, Act act) const {
    const int held = ::fcntl(fd, F_DUPFD_CLOEXEC, 0);
    if (held < 0) return;
    if (server_peer_of(held) == key) act(held);
    ::close(held);
  }
  void cut(int fd, const std::string& key) const {
    on_connection(fd, key, [](int held) { ::shutdown(held, SHUT_RDWR); });
  }
  /// Cuts an answering connection whose peer takes the response too slowly (kResponseGrace).
  void check_response_rate(int fd, const std::string& key, Connection& c, Clock::time_point now) const {
    on_connection(fd, key, [&](int held) {
      const std::optional<uint64_t> acked = tcp_bytes_acked(held);
      if (!acked) return;
      if (!c.acked_at_answer) c.acked_at_answer = *acked;
      const double seconds = std::chrono::duration<double>(now - *c.answering_since).count();
      if (now - *c.answering_since > kResponseGrace &&
          static_cast<double>(*acked - *c.acked_at_answer) < kMinResponseBytesPerS * seconds)
        ::shutdown(held, SHUT_RDWR);
    });
  }
  void watch() {
    std::unique_lock lock(mutex_);
    while (!quit_) {
      wake_.wait_for(lock, kWatchdogPeriod);
      const auto now = Clock::now();
      for (auto& [key, c] : connections_) c.seen = false;
      std::vector<std::tuple<Clock::time_point, int, std::string>> reading;  // (since, fd, key)
      for (const auto& [fd, key] : scan()) {
        Connection& c = connections_[key];  // new: reading since now
        c.seen = true;
        if (stopping_ || (c.reading && now - c.reading_since > kRequestReadLimit)) cut(fd, key);
        else if (c.reading) reading.emplace_back(c.reading_since, fd, key);
        else if (c.answering_since) check_response_rate(fd, key, c, now);
      }
      std::erase_if(connections_, [](const auto& entry) { return !entry.second.seen; });
      if (reading.size() <= kMaxReadingConnections) continue;
      std::sort(reading.begin(), reading.end());
      for (size_t k = 0; k + kMaxReadingConnections < reading.size(); ++k)
        cut(std::get<1>(reading[k]), std::get<2>(reading[k]));
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::map<std::string, Connection> connections_;
  int port_ = 0;
  bool stopping_ = false, quit_ = false;
  std::thread watchdog_;
};


ViewerServer::ViewerServer(const std::string& host, int port)
    : guard_(std::make_unique<ConnectionGuard>()), server_(std::make_unique<httplib::Server>()), host_(host) {
  httplib::Server& server = *server_;
  server.new_task_queue = [] { return new httplib::ThreadPool(kServerThreads); };
  server.set_read_timeout(kReadTimeoutS, 0);
  server.set_write_timeout(10, 0);
  server.set_keep_alive_timeout(kReadTimeoutS);
  server.set_keep_alive_max_count(kKeepAliveMaxRequests);
  server.set_payload_max_length(1 << 16);  // GET only: no request body worth reading
  server.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    guard_->request_read(req.remote_addr, req.remote_port);
    // A body would be read after this point, outside the request time limit: GET has none.
    const bool has_body = (req.has_header("Content-Length") && req.get_header_value("Content-Length") != "0") ||
                          req.has_header("Transfer-Encoding");
    if (has_body) {
      res.status = 400;
      res.set_header("Connection", "close");
      res.set_content("a request body is not accepted\n", "text/plain");
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
  server.set_logger([this](const httplib::Request& req, const httplib::Response&) {
    guard_->response_sent(req.remote_addr, req.remote_port);
  });
  // Outputs change between runs (and a live map every second): never show a stale one.
  server.set_post_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    guard_->answering(req.remote_addr, req.remote_port);
  });
  server.Get("/", [](const httplib::Request&, httplib::Response& res) { res.set_redirect("/viewer/index.html"); });
  if (port == 0) {
    port_ = server.bind_to_any_port(host);
    if (port_ <= 0) throw Error("--host", "cannot listen on " + host);
  } else if (!server.bind_to_port(host, port)) {
    throw Error("--port", "cannot listen on " + host + ":" + std::to_string(port) + " (in use?)");
  } else {
    port_ = port;
  }
  guard_->watch_port(port_);
}

ViewerServer::~ViewerServer() { stop(); }

httplib::Server& ViewerServer::http() { return *server_; }

void ViewerServer::print_urls(const std::string& what) const {
  std::printf("%s\n", what.c_str());
  if (host_ == "0.0.0.0" || host_ == "::" || host_.empty()) {
    char name[256] = {0};
    ::gethostname(name, sizeof name - 1);
    std::fprintf(stderr,
                 "semap: warning: --host %s listens on every network interface: anyone who can reach this "
                 "machine on port %d can read it\n",
                 host_.c_str(), port_);
    std::printf("  open http://127.0.0.1:%d/viewer/index.html on this machine, or http://%s:%d/viewer/index.html from "
                "another one   (Ctrl-C stops)\n",
                port_, name, port_);
  } else {
    if (!is_loopback(host_))
      std::fprintf(stderr, "semap: warning: --host %s is reachable from other machines: they can read it\n",
                   host_.c_str());
    std::printf("  open http://%s:%d/viewer/index.html   (Ctrl-C stops)\n", url_host(host_).c_str(), port_);
  }
  std::fflush(stdout);
}

void ViewerServer::run_until_interrupted() {
  // Ctrl-C / SIGTERM only set a flag (io/output_folder); this thread turns it into stop().
  std::atomic<bool> listening_done{false};
  std::thread watcher([&] {
    while (interrupt_signal() == 0 && !listening_done) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    guard_->stop_all();
    server_->stop();
  });
  const bool ok = server_->listen_after_bind();
  listening_done = true;
  watcher.join();
  if (!ok && interrupt_signal() == 0) throw Error("semap view", "the server stopped unexpectedly");
}

void ViewerServer::start() {
  thread_ = std::thread([this] { server_->listen_after_bind(); });
}

void ViewerServer::stop() {
  guard_->stop_all();
  server_->stop();
  if (thread_.joinable()) thread_.join();
}
#endif

}  // namespace semap::app
