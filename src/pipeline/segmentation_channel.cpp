#include "pipeline/segmentation_channel.hpp"

#include <spdlog/spdlog.h>

#include "semap/core/error.hpp"

namespace semap {

void SegmentationResults::put(size_t sequence, std::optional<SegmentationResult> result) {
  std::lock_guard lock(mutex_);
  results_[sequence] = std::move(result);
  ready_.notify_all();
}

std::optional<std::optional<SegmentationResult>> SegmentationResults::take(size_t sequence, bool block) {
  std::unique_lock lock(mutex_);
  if (block) ready_.wait(lock, [&] { return results_.count(sequence) > 0; });
  const auto it = results_.find(sequence);
  if (it == results_.end()) return std::nullopt;
  auto out = std::move(it->second);
  results_.erase(it);
  return out;
}

SegmentationChannel::SegmentationChannel(Segmenter* segmenter, Options options, StageTimings& timings,
                                         FailureSink on_first_failure)
    : segmenter_(segmenter),
      options_(std::move(options)),
      timings_(timings),
      on_first_failure_(std::move(on_first_failure)),
      stage_(std::make_unique<Stage<Frame>>(options_.threaded, options_.queue_size,
                                            [this](Frame& f) { segment(f); })) {}

void SegmentationChannel::send(const Frame& frame) {
  if (!segmenter_) throw Error("Mapper", "segmentation scheduled without a segmenter");
  ++segmented_;
  if (options_.when_busy == WhenBusy::wait) return stage_->push(frame);
  if (auto oldest = stage_->push_drop_oldest(frame)) {
    ++dropped_;
    --segmented_;
    results_.put(oldest->index, std::nullopt);
  }
}

void SegmentationChannel::put(size_t sequence, std::optional<SegmentationResult> result) {
  ++segmented_;
  if (result) result->frame_index = sequence;
  results_.put(sequence, std::move(result));
}

void SegmentationChannel::segment(Frame& frame) {
  const StageStart t0 = StageStart::now();
  try {
    SegmentationResult r = segmenter_->segment(frame);
    r.frame_index = frame.index;
    timings_.add(options_.timing_name, t0, frame.index);
    results_.put(frame.index, std::move(r));
  } catch (const std::exception& e) {
    spdlog::warn("segmentation of {} failed: {}",
                 frame.rgb_path.empty() ? "frame " + std::to_string(frame.index) : frame.rgb_path, e.what());
    if (failed_++ == 0 && on_first_failure_) on_first_failure_(e.what());
    results_.put(frame.index, std::nullopt);
  }
}

}  // namespace semap
