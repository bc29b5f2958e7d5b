#pragma once
// A progress line for long work: "label  120/500  35.2 fps  ETA 0:11  extra" on stderr,
// redrawn at most a few times a second; silent when stderr is not a terminal unless forced.
#include <chrono>
#include <string>

namespace semap {

class Progress {
 public:
  Progress(std::string label, size_t total, std::string unit = "frames");
  /// Reports `done` items; `extra` is appended (e.g. "objects 12").
  void update(size_t done, const std::string& extra = "");
  /// Prints the final line with total time and mean rate.
  void finish(const std::string& extra = "");
  double elapsed_s() const;
  /// Quiet mode (tests) or forced output even without a terminal (CI logs).
  static void set_mode(int mode);  // 0 = auto, 1 = always, -1 = never

 private:
  void print(size_t done, const std::string& extra, bool final_line);
  std::string label_, unit_;
  size_t total_;
  std::chrono::steady_clock::time_point start_, last_print_;
  bool printed_ = false;
};

/// "1:05" / "0:07" / "1:02:03".
std::string format_duration(double seconds);

}  // namespace semap
