// AsyncSegmenter scheduling and the `semap segment` CLI.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "semap/core/error.hpp"
#include "segmentation/async_segmenter.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

// Sleeps a fixed time, returns the frame's labels; throws on frame index 99.
class SlowSegmenter : public Segmenter {
 public:
  explicit SlowSegmenter(int ms) : ms_(ms) {}
  SegmentationResult segment(const Frame& frame) override {
    if (frame.index == 99) throw Error("slow", "boom");
    std::this_thread::sleep_for(std::chrono::milliseconds(ms_));
    SegmentationResult r;
    r.labels = cv::Mat(4, 4, CV_8UC1, cv::Scalar(int(frame.index % 200)));
    return r;
  }
  std::string name() const override { return "slow"; }

 private:
  int ms_;
};

Frame frame(size_t i) {
  Frame f;
  f.index = i;
  f.timestamp = i / 30.0;
  f.rgb = cv::Mat(4, 4, CV_8UC3, cv::Scalar::all(0));
  return f;
}

TEST(AsyncSegmenter, SubmitReturnsAtOnceKeepsLatestAndTagsResults) {
  SegmentationConfig cfg;
  cfg.async_queue_size = 1;
  cfg.every_n_frames = 5;
  AsyncSegmenter async(std::make_unique<SlowSegmenter>(50), cfg);
  EXPECT_TRUE(async.should_run(0, false));
  EXPECT_FALSE(async.should_run(3, false));
  EXPECT_TRUE(async.should_run(3, true));
  EXPECT_TRUE(async.should_run(10, false));
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < 10; ++i) async.submit(frame(i));
  const double submit_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(submit_ms, 40.0);  // never waits for the 50 ms network
  const auto results = async.drain();
  // Frame 0 may already be in progress; the rest are dropped one by one and 9 (the latest) is kept.
  ASSERT_GE(results.size(), 1u);
  EXPECT_LE(results.size(), 2u);
  EXPECT_EQ(results.back().frame_index, 9u);
  EXPECT_DOUBLE_EQ(results.back().timestamp, 9 / 30.0);
  EXPECT_EQ(results.back().labels.at<uint8_t>(0, 0), 9);
  EXPECT_EQ(async.dropped() + async.completed(), 10u);
  EXPECT_FALSE(async.poll().has_value());
  // Errors of the segmenter reach the caller.
  async.submit(frame(99));
  EXPECT_THROW(async.drain(), Error);
}

TEST(SegmentCli, WritesFourFilesPerImageAndFailsCleanly) {
  const auto model = test::models_dir() / "yolov8n-seg-320.onnx";
  SEMAP_REQUIRE_DATA(root, "ycb_video_0000");
  if (!std::filesystem::exists(model)) GTEST_SKIP();
  if (!std::filesystem::exists(test::semap_executable())) GTEST_SKIP() << "semap not built";
  test::TempDir out;
  const auto image = root / "data/0000/000001-color.png";
  const auto r = test::run_command(test::semap_executable().string() + " segment " + image.string() +
                                   " --model yolo:" + model.string() + " --out " + out.path().string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* ext : {".label.png", ".instances.png", ".json", ".overlay.png"})
    EXPECT_TRUE(std::filesystem::exists(out / (std::string("000001-color") + ext))) << ext;
  const cv::Mat label = cv::imread((out / "000001-color.label.png").string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(label.type(), CV_16UC1);
  EXPECT_GT(cv::countNonZero(label == id(Label::kCup)), 1000);
  std::ifstream in(out / "000001-color.json");
  const auto j = nlohmann::json::parse(in);
  bool cup = false;
  for (const auto& inst : j.at("instances")) {
    cup |= inst.at("class") == "cup";
    EXPECT_EQ(inst.at("box").size(), 4u);
    EXPECT_TRUE(inst.contains("score") && inst.contains("class_id") && inst.contains("id"));
  }
  EXPECT_TRUE(cup);
  const auto bad = test::run_command(test::semap_executable().string() + " segment " + image.string() +
                                     " --model yolo:/nonexistent/m.onnx --out " + out.path().string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("/nonexistent/m.onnx"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace semap
