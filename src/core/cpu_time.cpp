#include "core/cpu_time.hpp"

#include <time.h>

#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

namespace semap {
namespace {

int64_t clock_ns(clockid_t id) {
  timespec t{};
  clock_gettime(id, &t);
  return static_cast<int64_t>(t.tv_sec) * 1000000000 + t.tv_nsec;
}

/// Entry times of the arenas a worker is in (nested task_arena::execute: more than one).
thread_local std::vector<std::pair<const ArenaWorkerCpu*, int64_t>> entered;

}  // namespace

double thread_cpu_ms() { return static_cast<double>(clock_ns(CLOCK_THREAD_CPUTIME_ID)) * 1e-6; }
double process_cpu_ms() { return static_cast<double>(clock_ns(CLOCK_PROCESS_CPUTIME_ID)) * 1e-6; }

ArenaWorkerCpu::ArenaWorkerCpu(tbb::task_arena& arena) : tbb::task_scheduler_observer(arena) {
  arena.initialize();
  observe(true);
}
ArenaWorkerCpu::ArenaWorkerCpu() { observe(true); }
ArenaWorkerCpu::~ArenaWorkerCpu() { observe(false); }

void ArenaWorkerCpu::on_scheduler_entry(bool is_worker) {
  if (is_worker) entered.emplace_back(this, clock_ns(CLOCK_THREAD_CPUTIME_ID));
}

void ArenaWorkerCpu::on_scheduler_exit(bool is_worker) {
  if (!is_worker) return;
  for (auto it = entered.rbegin(); it != entered.rend(); ++it)
    if (it->first == this) {
      total_ns_.fetch_add(clock_ns(CLOCK_THREAD_CPUTIME_ID) - it->second, std::memory_order_relaxed);
      entered.erase(std::next(it).base());
      return;
    }
}

double opencv_workers_cpu_ms() {
  // OpenCV runs cv::parallel_for_ in one task_arena of its own (TBB backend), not reachable
  // from here: an observer made inside one of its loops observes the arena it is made in.
  // Never destroyed (OpenCV's arena lives until exit).
  static const ArenaWorkerCpu* const observer = [] {
    ArenaWorkerCpu* made = nullptr;
    std::once_flag once;
    cv::parallel_for_(cv::Range(0, 2), [&](const cv::Range&) { std::call_once(once, [&] { made = new ArenaWorkerCpu(); }); });
    return made;
  }();
  return observer->total_ms();
}

double thread_and_helpers_cpu_ms() {
  thread_local const std::unique_ptr<ArenaWorkerCpu> helpers = std::make_unique<ArenaWorkerCpu>();
  return thread_cpu_ms() + helpers->total_ms();
}

}  // namespace semap
