#include "core/progress.hpp"

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>

namespace semap {
namespace {
std::atomic<int> g_mode{0};
bool enabled() {
  const int m = g_mode.load();
  if (m != 0) return m > 0;
  return isatty(fileno(stderr));
}
}  // namespace

void Progress::set_mode(int mode) { g_mode = mode; }

Progress::Progress(std::string label, size_t total, std::string unit)
    : label_(std::move(label)), unit_(std::move(unit)), total_(total),
      start_(std::chrono::steady_clock::now()), last_print_(start_) {}

double Progress::elapsed_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = std::lround(s);
  char buf[32];
  if (t >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
  return buf;
}

void Progress::update(size_t done, const std::string& extra) {
  const auto now = std::chrono::steady_clock::now();
  if (printed_ && now - last_print_ < std::chrono::milliseconds(250) && done < total_) return;
  last_print_ = now;
  print(done, extra, false);
}

void Progress::finish(const std::string& extra) { print(total_, extra, true); }

void Progress::print(size_t done, const std::string& extra, bool final_line) {
  if (!enabled()) return;
  const double el = elapsed_s();
  const double rate = el > 0 ? done / el : 0.0;
  const bool tty = isatty(fileno(stderr));
  std::string line;
  char buf[160];
  if (final_line) {
    std::snprintf(buf, sizeof buf, "%s  %zu %s in %s  (%.1f %s/s)", label_.c_str(), done, unit_.c_str(),
                  format_duration(el).c_str(), rate, unit_ == "frames" ? "frames" : unit_.c_str());
  } else {
    const double eta = rate > 0 && total_ > done ? (total_ - done) / rate : 0.0;
    std::snprintf(buf, sizeof buf, "%s  %zu/%zu %s  %.1f fps  ETA %s", label_.c_str(), done, total_,
                  unit_.c_str(), rate, format_duration(eta).c_str());
  }
  line = buf;
  if (!extra.empty()) line += "  " + extra;
  if (tty)
    std::fprintf(stderr, "\r\033[K%s%s", line.c_str(), final_line ? "\n" : "");
  else if (final_line || !printed_ || done % 50 == 0)
    std::fprintf(stderr, "%s\n", line.c_str());
  std::fflush(stderr);
  printed_ = true;
}

}  // namespace semap
