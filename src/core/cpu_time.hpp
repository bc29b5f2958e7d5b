#pragma once
// CPU time of pipeline stages (issue 20: the per-stage CPU budget). A stage's CPU is its own
// thread's (CLOCK_THREAD_CPUTIME_ID) plus what TBB worker threads spend in the arenas it runs
// work in: its thread's own implicit arena (cv::parallel_for_ and tbb::parallel_for called on
// that thread) and explicit arenas such as an integrator's.
#include <tbb/task_arena.h>
#include <tbb/task_scheduler_observer.h>

#include <atomic>
#include <cstdint>

namespace semap {

/// CPU milliseconds of the calling thread.
double thread_cpu_ms();
/// CPU milliseconds of the whole process (every thread).
double process_cpu_ms();

/// Sums the CPU time TBB worker threads spend inside one arena (entry to exit, including the
/// spinning before they leave). Workers' time is added when they leave the arena.
class ArenaWorkerCpu final : public tbb::task_scheduler_observer {
 public:
  /// Observes `arena` (initialised here if it was not).
  explicit ArenaWorkerCpu(tbb::task_arena& arena);
  /// Observes the calling thread's own implicit arena.
  ArenaWorkerCpu();
  ~ArenaWorkerCpu() override;
  ArenaWorkerCpu(const ArenaWorkerCpu&) = delete;
  ArenaWorkerCpu& operator=(const ArenaWorkerCpu&) = delete;

  double total_ms() const { return static_cast<double>(total_ns_.load(std::memory_order_relaxed)) * 1e-6; }
  void on_scheduler_entry(bool is_worker) override;
  void on_scheduler_exit(bool is_worker) override;

 private:
  std::atomic<int64_t> total_ns_{0};
};

/// CPU milliseconds of the worker threads in OpenCV's TBB arena (cv::parallel_for_: the DNN
/// segmenters, image operations) since the first call, which starts observing it. Workers
/// there serve every thread that calls OpenCV, so this is not split by stage.
double opencv_workers_cpu_ms();

/// CPU milliseconds of the calling thread plus its TBB helpers so far: the workers' time in
/// this thread's implicit arena (observed from this thread's first call on).
double thread_and_helpers_cpu_ms();

}  // namespace semap
