#pragma once
// One segmentation network on its own frames (issue 38): its schedule (every N-th frame and the
// tracking keyframes), its stage (a thread behind a bounded queue, or inline with
// pipeline.threads = 1) and its results, keyed by the Mapper's sequence number, which fusion
// takes in frame order. A panoptic run has two channels, so the heavier semantic network runs
// on fewer frames than the instance network and neither stalls the other or tracking.
//
// Thread safety: wants/send/put/close from the Mapper's caller thread (the producer); take from
// the fusion thread; the handler runs on the channel's own thread. Counters are atomic.
#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "pipeline/stage.hpp"
#include "semap/pipeline/stage_timer.hpp"
#include "semap/segmentation/segmentation_config.hpp"
#include "semap/segmentation/segmenter.hpp"

namespace semap {

/// Segmentation results keyed by sequence number, from a segmentation stage (or the caller) to
/// fusion. nullopt inside means "dropped or failed".
class SegmentationResults {
 public:
  void put(size_t sequence, std::optional<SegmentationResult> result);
  /// The result if it has arrived (block: waits for it). Thread-safe.
  std::optional<std::optional<SegmentationResult>> take(size_t sequence, bool block);

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::map<size_t, std::optional<SegmentationResult>> results_;
};

/// Which frames a network segments.
struct SegmentationSchedule {
  int every_n_frames = 1;
  bool on_keyframes = true;
  bool wants(size_t sequence, bool keyframe) const {
    return (keyframe && on_keyframes) || sequence % static_cast<size_t>(every_n_frames) == 0;
  }
};

class SegmentationChannel {
 public:
  struct Options {
    std::string timing_name;  ///< StageTimings key, e.g. "segmentation"
    SegmentationSchedule schedule;
    bool threaded = false;
    size_t queue_size = 1;
    WhenBusy when_busy = WhenBusy::wait;
  };
  /// Called once, with the first failure's message (from the channel's thread).
  using FailureSink = std::function<void(const std::string& what)>;

  /// `segmenter` must outlive the channel and is called from the channel's thread only; null:
  /// results come only through put() (the caller's own segmentation).
  SegmentationChannel(Segmenter* segmenter, Options options, StageTimings& timings, FailureSink on_first_failure);

  const SegmentationSchedule& schedule() const { return options_.schedule; }
  /// Sends the frame to the network. With when_busy = drop_oldest and a full queue, the oldest
  /// waiting frame is dropped and recorded as nullopt (fusion then fuses it without these labels).
  void send(const Frame& frame);
  /// A result that did not come from this channel's network (the caller's own segmentation).
  void put(size_t sequence, std::optional<SegmentationResult> result);
  std::optional<std::optional<SegmentationResult>> take(size_t sequence, bool block) {
    return results_.take(sequence, block);
  }
  /// Waits for every frame sent to be segmented. Idempotent.
  void close() { stage_->close(); }

  size_t segmented() const { return segmented_; }
  size_t dropped() const { return dropped_; }
  size_t failed() const { return failed_; }

 private:
  void segment(Frame& frame);  ///< never throws: fusion waits for a result of every frame sent

  Segmenter* segmenter_;
  const Options options_;
  StageTimings& timings_;
  FailureSink on_first_failure_;
  SegmentationResults results_;
  std::atomic<size_t> segmented_{0}, dropped_{0}, failed_{0};
  std::unique_ptr<Stage<Frame>> stage_;  ///< last: destroyed (drained) first
};

}  // namespace semap
