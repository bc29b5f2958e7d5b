#pragma once
// Runs a Segmenter on its own worker thread so tracking and fusion never wait for the
// network (issue 5 "Scheduling"). submit() returns at once; results come back through poll()
// tagged with the frame index and timestamp they were computed on.
// Queue policy: at most config.async_queue_size frames wait; when a new frame arrives and the
// queue is full, the OLDEST waiting frame is dropped (keep-latest: the map wants the most
// recent view, a stale one is worth less). The frame being processed is never interrupted.
// Scheduling: should_run(index, is_keyframe) is true on every every_n_frames-th frame and, with
// on_keyframes, on keyframes; the caller decides whether to submit.
#include <condition_variable>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "semap/segmentation/segmentation_config.hpp"
#include "semap/segmentation/segmenter.hpp"

namespace semap {

class AsyncSegmenter {
 public:
  AsyncSegmenter(std::unique_ptr<Segmenter> segmenter, const SegmentationConfig& config);
  ~AsyncSegmenter();  ///< stops the worker after the frame in progress; waiting frames are discarded
  AsyncSegmenter(const AsyncSegmenter&) = delete;
  AsyncSegmenter& operator=(const AsyncSegmenter&) = delete;

  bool should_run(size_t frame_index, bool is_keyframe) const;
  /// Queues a copy of the frame's images (shallow cv::Mat copies: the caller must not write
  /// into them afterwards). Returns false when an older waiting frame was dropped for it.
  bool submit(const Frame& frame);
  /// Next finished result, if any (never blocks). Rethrows an exception of the segmenter.
  std::optional<SegmentationResult> poll();
  /// Blocks until every submitted frame is processed, then returns all unpolled results in order.
  std::vector<SegmentationResult> drain();

  size_t submitted() const { return submitted_; }
  size_t dropped() const;
  size_t completed() const;
  const Segmenter& segmenter() const { return *segmenter_; }

 private:
  void worker();

  std::unique_ptr<Segmenter> segmenter_;
  SegmentationConfig config_;
  mutable std::mutex mutex_;
  std::condition_variable work_cv_, done_cv_;
  std::deque<Frame> waiting_;
  std::deque<SegmentationResult> results_;
  std::exception_ptr error_;
  bool busy_ = false, stop_ = false;
  size_t submitted_ = 0, dropped_ = 0, completed_ = 0;
  std::thread thread_;
};

}  // namespace semap
