#include "semap/pipeline/stage_timer.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <numeric>

namespace semap {

void StageTimings::add(const std::string& stage, double ms) {
  std::lock_guard lock(mutex_);
  auto [it, inserted] = samples_.try_emplace(stage);
  if (inserted) order_.push_back(stage);
  it->second.push_back(ms);
}

TimingSummary StageTimings::summary(const std::string& stage) const {
  std::lock_guard lock(mutex_);
  TimingSummary s;
  const auto it = samples_.find(stage);
  if (it == samples_.end() || it->second.empty()) return s;
  std::vector<double> v = it->second;
  std::sort(v.begin(), v.end());
  s.count = v.size();
  s.total_ms = std::accumulate(v.begin(), v.end(), 0.0);
  s.mean_ms = s.total_ms / v.size();
  s.median_ms = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  s.p95_ms = v[std::min(v.size() - 1, static_cast<size_t>(0.95 * (v.size() - 1) + 0.5))];
  return s;
}

std::vector<std::string> StageTimings::stages() const {
  std::lock_guard lock(mutex_);
  return order_;
}

size_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<size_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

}  // namespace semap
