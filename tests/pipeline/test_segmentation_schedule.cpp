// The segmentation hand-off when the network is busy (segmentation.when_busy, documented in
// segmentation_config.hpp): `drop_oldest` never makes add_frame wait and drops the OLDEST
// waiting request, so the newest frames are the ones segmented; `wait` drops nothing and makes
// add_frame wait for room. A segmenter that blocks until the test opens it stands for a busy
// network. Threaded pipeline (pipeline.threads = 2): this file also runs under ThreadSanitizer.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <future>
#include <mutex>
#include <set>

#include "semap/mapper.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

using namespace std::chrono_literals;

/// Blocks every segment() call until open(); records the frames it was called on.
class GatedSegmenter : public Segmenter {
 public:
  SegmentationResult segment(const Frame& frame) override {
    std::unique_lock lock(mutex_);
    seen_.insert(frame.index);
    changed_.notify_all();
    changed_.wait(lock, [&] { return open_; });
    SegmentationResult r;
    r.labels = cv::Mat(frame.depth.size(), CV_8UC1, cv::Scalar(static_cast<int>(Label::kTable)));
    return r;
  }
  std::string name() const override { return "gated"; }
  void open() {
    std::lock_guard lock(mutex_);
    open_ = true;
    changed_.notify_all();
  }
  /// Waits until segment() was entered for `index` (false after 30 s).
  bool wait_until_seen(size_t index) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, 30s, [&] { return seen_.count(index) > 0; });
  }
  std::set<size_t> seen() const {
    std::lock_guard lock(mutex_);
    return seen_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool open_ = false;
  std::set<size_t> seen_;
};

constexpr size_t kFrames = 12;
constexpr int kQueue = 2;  // segmentation.async_queue_size

CameraModel small_camera() {
  CameraModel camera;
  camera.depth = {60.0, 60.0, 31.5, 23.5, 64, 48};
  camera.depth_scale = 1000.0;
  return camera;
}

/// A wall 1.5 m in front of a camera that slides 1 cm per frame.
std::pair<Frame, FrameHints> wall_frame(size_t index) {
  Frame frame;
  frame.index = index;
  frame.timestamp = 0.1 * static_cast<double>(index);
  frame.depth = cv::Mat(48, 64, CV_32FC1, cv::Scalar(1.5));
  frame.rgb = cv::Mat(48, 64, CV_8UC3, cv::Scalar(90, 120, 150));
  FrameHints hints;
  Pose T_world_camera = Pose::Identity();
  T_world_camera.translation().x() = 0.01 * static_cast<double>(index);
  hints.T_world_camera = T_world_camera;
  return {frame, hints};
}

SemapConfig busy_config(WhenBusy policy) {
  SemapConfig config;
  config.pipeline.threads = 2;
  config.tsdf.voxel_size = 0.05;
  config.segmentation.every_n_frames = 1;
  config.segmentation.async_queue_size = kQueue;
  config.segmentation.when_busy = policy;
  return config;
}

/// Feeds frames [first, kFrames) on another thread; `fed` counts the add_frame calls returned.
std::future<void> feed_async(Mapper& mapper, size_t first, std::atomic<size_t>& fed) {
  return std::async(std::launch::async, [&mapper, first, &fed] {
    for (size_t i = first; i < kFrames; ++i) {
      auto [frame, hints] = wall_frame(i);
      mapper.add_frame(frame, hints);
      ++fed;
    }
  });
}

TEST(SegmentationSchedule, DropOldestNeverWaitsAndKeepsTheNewestRequests) {
  auto segmenter = std::make_unique<GatedSegmenter>();
  GatedSegmenter& gate = *segmenter;
  Mapper mapper(busy_config(WhenBusy::drop_oldest), small_camera(), std::move(segmenter));
  auto [first, hints] = wall_frame(0);
  mapper.add_frame(first, hints);
  ASSERT_TRUE(gate.wait_until_seen(0));  // the network is now busy with frame 0

  std::atomic<size_t> fed{0};
  auto feeding = feed_async(mapper, 1, fed);
  const bool returned = feeding.wait_for(60s) == std::future_status::ready;
  gate.open();  // never leave the feeder blocked, whatever the outcome
  feeding.get();
  ASSERT_TRUE(returned) << "add_frame waited for a busy network under drop_oldest (" << fed << " fed)";
  mapper.finish();

  const MapperStats stats = mapper.stats();
  // Frame 0 was in the network; of the 11 later requests the queue kept the 2 newest.
  EXPECT_EQ(stats.segmentations_dropped, kFrames - 1 - kQueue);
  EXPECT_EQ(gate.seen(), (std::set<size_t>{0, kFrames - 2, kFrames - 1}));
  EXPECT_EQ(stats.segmented_frames, 1u + kQueue);
  EXPECT_EQ(stats.frames_fused, kFrames) << "a frame whose request was dropped is fused without labels";
}

TEST(SegmentationSchedule, WaitDropsNothingAndHoldsTheCallerWhileTheQueueIsFull) {
  auto segmenter = std::make_unique<GatedSegmenter>();
  GatedSegmenter& gate = *segmenter;
  Mapper mapper(busy_config(WhenBusy::wait), small_camera(), std::move(segmenter));
  auto [first, hints] = wall_frame(0);
  mapper.add_frame(first, hints);
  ASSERT_TRUE(gate.wait_until_seen(0));

  std::atomic<size_t> fed{0};
  auto feeding = feed_async(mapper, 1, fed);
  const bool held = feeding.wait_for(1s) == std::future_status::timeout;
  const size_t fed_while_busy = fed;
  gate.open();
  feeding.get();
  mapper.finish();

  EXPECT_TRUE(held) << "every frame went through while the network was blocked";
  EXPECT_EQ(fed_while_busy, static_cast<size_t>(kQueue)) << "the queue holds kQueue requests, then add_frame waits";
  const MapperStats stats = mapper.stats();
  EXPECT_EQ(stats.segmentations_dropped, 0u);
  EXPECT_EQ(gate.seen().size(), kFrames);
  EXPECT_EQ(stats.segmented_frames, kFrames);
  EXPECT_EQ(stats.frames_fused, kFrames);
}

}  // namespace
}  // namespace semap
