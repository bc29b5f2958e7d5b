#include "semap/pipeline/stage_timer.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <numeric>

#include "core/cpu_time.hpp"

namespace semap {

void StageTimings::add(const std::string& stage, double ms, std::optional<size_t> frame_index) {
  std::lock_guard lock(mutex_);
  auto [it, inserted] = samples_.try_emplace(stage);
  if (inserted) order_.push_back(stage);
  it->second.push_back({ms, frame_index});
}

StageStart StageStart::now() { return {std::chrono::steady_clock::now(), thread_and_helpers_cpu_ms()}; }

double StageStart::wall_ms_since() const {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall).count();
}

void StageTimings::add(const std::string& stage, const StageStart& start, std::optional<size_t> frame_index,
                       double extra_cpu_ms) {
  const double wall_ms = start.wall_ms_since();
  const double cpu_ms = thread_and_helpers_cpu_ms() - start.cpu_ms + extra_cpu_ms;
  add(stage, wall_ms, frame_index);
  std::lock_guard lock(mutex_);
  auto& [count, total] = cpu_[stage];
  ++count;
  total += cpu_ms;
}

TimingSummary StageTimings::summary(const std::string& stage) const {
  std::lock_guard lock(mutex_);
  TimingSummary s;
  const auto it = samples_.find(stage);
  if (it == samples_.end() || it->second.empty()) return s;
  std::vector<double> v;
  v.reserve(it->second.size());
  for (const StageSample& sample : it->second) v.push_back(sample.wall_ms);
  std::sort(v.begin(), v.end());
  s.count = v.size();
  s.total_ms = std::accumulate(v.begin(), v.end(), 0.0);
  s.mean_ms = s.total_ms / v.size();
  s.median_ms = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  s.p95_ms = v[std::min(v.size() - 1, static_cast<size_t>(0.95 * (v.size() - 1) + 0.5))];
  if (const auto c = cpu_.find(stage); c != cpu_.end()) {
    s.cpu_count = c->second.first;
    s.cpu_total_ms = c->second.second;
    s.cpu_mean_ms = s.cpu_total_ms / static_cast<double>(std::max<size_t>(1, s.cpu_count));
  }
  return s;
}

std::vector<std::string> StageTimings::stages() const {
  std::lock_guard lock(mutex_);
  return order_;
}

std::vector<StageSample> StageTimings::samples(const std::string& stage) const {
  std::lock_guard lock(mutex_);
  const auto it = samples_.find(stage);
  return it == samples_.end() ? std::vector<StageSample>{} : it->second;
}

size_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<size_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

}  // namespace semap
