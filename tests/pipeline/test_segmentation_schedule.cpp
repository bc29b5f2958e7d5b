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
#include <map>
#include <set>

#include "segmentation/panoptic_segmenter.hpp"
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

/// Records the frames it ran on. Semantic: `wall` on the right two thirds of the image, nothing on
/// the left third; instance: one cup covering the left third.
class RecordingSegmenter : public Segmenter {
 public:
  explicit RecordingSegmenter(bool instances) : instances_(instances) {}
  SegmentationResult segment(const Frame& frame) override {
    {
      std::lock_guard lock(mutex_);
      seen_.insert(frame.index);
    }
    const cv::Rect left(0, 0, frame.depth.cols / 3, frame.depth.rows);
    SegmentationResult r;
    if (!instances_) {
      r.labels = cv::Mat(frame.depth.size(), CV_8UC1, cv::Scalar(static_cast<int>(Label::kWall)));
      r.labels(left).setTo(0);
      return r;
    }
    InstanceDetection cup;
    cup.id = 1;
    cup.class_id = static_cast<ClassId>(Label::kCup);
    cup.score = 0.9f;
    cup.mask = cv::Mat::zeros(frame.depth.size(), CV_8UC1);
    cup.mask(left).setTo(255);
    cup.box = left;
    r.instances.push_back(cup);
    return r;
  }
  std::string name() const override { return instances_ ? "instances" : "semantic"; }
  std::set<size_t> seen() const {
    std::lock_guard lock(mutex_);
    return seen_;
  }

 private:
  const bool instances_;
  mutable std::mutex mutex_;
  std::set<size_t> seen_;
};

/// Issue 38: each network of a panoptic segmenter on its own frames. The instance network follows
/// segmentation.every_n_frames and alone feeds the object map; the semantic network follows
/// segmentation.panoptic.semantic_every_n_frames; the TSDF gets the labels of both.
void expect_networks_on_their_own_frames(int threads) {
  SemapConfig config;
  config.pipeline.threads = threads;
  config.tsdf.voxel_size = 0.05;
  config.segmentation.every_n_frames = 4;
  config.segmentation.panoptic.semantic_every_n_frames = 3;
  // The cup is painted on the wall plane, where the geometric label rules would rightly give the
  // plane's label back (tsdf/label_priors.hpp); this test is about the schedule.
  config.tsdf.label_prior_normals = config.tsdf.label_prior_heights = config.tsdf.label_prior_regions = false;
  auto semantic = std::make_unique<RecordingSegmenter>(false);
  auto instance = std::make_unique<RecordingSegmenter>(true);
  const RecordingSegmenter& semantic_net = *semantic;
  const RecordingSegmenter& instance_net = *instance;
  Mapper mapper(config, small_camera(),
                std::make_unique<PanopticSegmenter>(std::move(semantic), std::move(instance), 0.5));
  for (size_t i = 0; i < kFrames; ++i) {
    auto [frame, hints] = wall_frame(i);
    mapper.add_frame(frame, hints);  // given poses: no tracking keyframes
  }
  mapper.finish();

  EXPECT_EQ(instance_net.seen(), (std::set<size_t>{0, 4, 8}));
  EXPECT_EQ(semantic_net.seen(), (std::set<size_t>{0, 3, 6, 9}));
  const MapperStats stats = mapper.stats();
  EXPECT_EQ(stats.segmented_frames, 3u);
  EXPECT_EQ(stats.semantic_segmented_frames, 4u);
  EXPECT_EQ(stats.object_frames, 3u) << "only the instance network's frames feed the object map";
  EXPECT_EQ(stats.frames_fused, kFrames);
  const TriangleMesh mesh = mapper.mesh();
  ASSERT_FALSE(mesh.vertices.labels.empty());
  std::map<ClassId, size_t> count;
  for (const ClassId label : mesh.vertices.labels) ++count[label];
  const double n = static_cast<double>(mesh.vertices.labels.size());
  EXPECT_GT(count[static_cast<ClassId>(Label::kWall)] / n, 0.4) << "semantic labels reached the TSDF";
  EXPECT_GT(count[static_cast<ClassId>(Label::kCup)] / n, 0.1) << "instance labels reached the TSDF";
}

TEST(SegmentationSchedule, PanopticNetworksRunOnTheirOwnFramesInline) { expect_networks_on_their_own_frames(1); }
TEST(SegmentationSchedule, PanopticNetworksRunOnTheirOwnFramesThreaded) { expect_networks_on_their_own_frames(2); }

}  // namespace
}  // namespace semap
