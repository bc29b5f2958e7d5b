#include "segmentation/async_segmenter.hpp"

#include "semap/core/error.hpp"

namespace semap {

AsyncSegmenter::AsyncSegmenter(std::unique_ptr<Segmenter> segmenter, const SegmentationConfig& config)
    : segmenter_(std::move(segmenter)), config_(config) {
  if (!segmenter_) throw Error("async segmenter", "no segmenter given");
  config_.validate();
  thread_ = std::thread([this] { worker(); });
}

AsyncSegmenter::~AsyncSegmenter() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    waiting_.clear();
  }
  work_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool AsyncSegmenter::should_run(size_t frame_index, bool is_keyframe) const {
  return frame_index % size_t(config_.every_n_frames) == 0 || (config_.on_keyframes && is_keyframe);
}

bool AsyncSegmenter::submit(const Frame& frame) {
  bool dropped = false;
  {
    std::lock_guard lock(mutex_);
    ++submitted_;
    while (int(waiting_.size()) >= config_.async_queue_size) {
      waiting_.pop_front();
      ++dropped_;
      dropped = true;
    }
    waiting_.push_back(frame);
  }
  work_cv_.notify_one();
  return !dropped;
}

std::optional<SegmentationResult> AsyncSegmenter::poll() {
  std::lock_guard lock(mutex_);
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  if (results_.empty()) return std::nullopt;
  SegmentationResult r = std::move(results_.front());
  results_.pop_front();
  return r;
}

std::vector<SegmentationResult> AsyncSegmenter::drain() {
  std::unique_lock lock(mutex_);
  done_cv_.wait(lock, [&] { return (waiting_.empty() && !busy_) || error_; });
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  std::vector<SegmentationResult> out(std::make_move_iterator(results_.begin()), std::make_move_iterator(results_.end()));
  results_.clear();
  return out;
}

size_t AsyncSegmenter::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

size_t AsyncSegmenter::completed() const {
  std::lock_guard lock(mutex_);
  return completed_;
}

void AsyncSegmenter::worker() {
  for (;;) {
    Frame frame;
    {
      std::unique_lock lock(mutex_);
      work_cv_.wait(lock, [&] { return stop_ || !waiting_.empty(); });
      if (stop_) return;
      frame = std::move(waiting_.front());
      waiting_.pop_front();
      busy_ = true;
    }
    std::optional<SegmentationResult> result;
    std::exception_ptr error;
    try {
      result = segmenter_->segment(frame);
      result->frame_index = frame.index;
      result->timestamp = frame.timestamp;
    } catch (...) {
      error = std::current_exception();
    }
    {
      std::lock_guard lock(mutex_);
      busy_ = false;
      if (result) {
        results_.push_back(std::move(*result));
        ++completed_;
      }
      if (error && !error_) error_ = error;
    }
    done_cv_.notify_all();
  }
}

}  // namespace semap
