#pragma once
// Per-stage timing statistics for report.json: mean / median / p95 ms and count, and the
// stage's CPU time where it was measured (its thread plus the TBB workers of its parallel
// loops, core/cpu_time.hpp): the per-stage CPU budget of issue 20.
#include <chrono>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace semap {

struct TimingSummary {
  size_t count = 0;
  double mean_ms = 0, median_ms = 0, p95_ms = 0, total_ms = 0;
  size_t cpu_count = 0;  ///< samples with a CPU time (0: the stage measured wall time only)
  double cpu_total_ms = 0, cpu_mean_ms = 0;
};

/// Start of a timed scope: wall clock and the calling thread's CPU (with its TBB helpers).
struct StageStart {
  std::chrono::steady_clock::time_point wall;
  double cpu_ms;
  static StageStart now();
  double wall_ms_since() const;
};

/// One timed call of a stage: its wall time and the frame it worked on (Frame::index; nullopt
/// for work of no one frame, e.g. the final pass). report.html plots them per frame (issue 43).
struct StageSample {
  double wall_ms = 0.0;
  std::optional<size_t> frame_index;
};

/// Every method is thread-safe (one mutex): stages on their own threads add concurrently.
class StageTimings {
 public:
  void add(const std::string& stage, double ms, std::optional<size_t> frame_index = std::nullopt);
  /// Wall and CPU time since `start` (same thread) of the work on `frame_index`; extra_cpu_ms:
  /// CPU spent for this stage on other threads (e.g. an integrator's own TBB arena).
  void add(const std::string& stage, const StageStart& start, std::optional<size_t> frame_index,
           double extra_cpu_ms = 0.0);
  TimingSummary summary(const std::string& stage) const;
  std::vector<std::string> stages() const;  ///< in first-seen order
  /// The stage's calls in the order they were added (a copy).
  std::vector<StageSample> samples(const std::string& stage) const;

 private:
  mutable std::mutex mutex_;
  std::vector<std::string> order_;
  std::map<std::string, std::vector<StageSample>> samples_;
  std::map<std::string, std::pair<size_t, double>> cpu_;  ///< samples, total ms
};

/// Times a scope into a StageTimings entry.
class ScopedStageTimer {
 public:
  ScopedStageTimer(StageTimings& timings, std::string stage)
      : timings_(timings), stage_(std::move(stage)), start_(StageStart::now()) {}
  ~ScopedStageTimer() { timings_.add(stage_, start_, std::nullopt); }

 private:
  StageTimings& timings_;
  std::string stage_;
  StageStart start_;
};

/// Peak resident set size of this process in bytes.
size_t peak_rss_bytes();

}  // namespace semap
