#pragma once
// Per-stage timing statistics for report.json: mean / median / p95 ms and count.
#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace semap {

struct TimingSummary {
  size_t count = 0;
  double mean_ms = 0, median_ms = 0, p95_ms = 0, total_ms = 0;
};

class StageTimings {
 public:
  void add(const std::string& stage, double ms);
  TimingSummary summary(const std::string& stage) const;
  std::vector<std::string> stages() const;  ///< in first-seen order

 private:
  mutable std::mutex mutex_;
  std::vector<std::string> order_;
  std::map<std::string, std::vector<double>> samples_;
};

/// Times a scope into a StageTimings entry.
class ScopedStageTimer {
 public:
  ScopedStageTimer(StageTimings& timings, std::string stage)
      : timings_(timings), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}
  ~ScopedStageTimer() {
    timings_.add(stage_, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count());
  }

 private:
  StageTimings& timings_;
  std::string stage_;
  std::chrono::steady_clock::time_point start_;
};

/// Peak resident set size of this process in bytes.
size_t peak_rss_bytes();

}  // namespace semap
