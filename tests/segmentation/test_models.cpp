// Real-model tests (issue 5): YOLO-seg on YCB-Video and 7-Scenes, DeepLab on a real frame,
// model loading errors.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"
#include "semap/segmentation/segmenter_factory.hpp"
#include "segmentation/semantic_segmenter.hpp"
#include "segmentation/yolo_segmenter.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

std::filesystem::path model(const std::string& name) { return test::models_dir() / name; }

#define REQUIRE_MODEL(var, name) SEMAP_REQUIRE_MODEL(var, name)

double mask_iou(const cv::Mat& a, const cv::Mat& b) {
  const int inter = cv::countNonZero(a & b), uni = cv::countNonZero(a | b);
  return uni ? double(inter) / uni : 0.0;
}

// Best mask IoU between any instance of class `c` and the reference mask.
double best_iou(const SegmentationResult& r, ClassId c, const cv::Mat& ref) {
  double best = 0;
  for (const auto& inst : r.instances)
    if (inst.class_id == c) best = std::max(best, mask_iou(inst.mask, ref));
  return best;
}

TEST(YoloSegmenter, FindsTheYcbMugAsCup) {
  SEMAP_REQUIRE_DATA(root, "ycb_video_0000");
  REQUIRE_MODEL(path, "yolov8n-seg-320.onnx");
  SegmentationConfig config;
  YoloSegmenter seg(path, config);
  EXPECT_EQ(seg.input_size(), cv::Size(320, 320));  // read from the ONNX graph
  EXPECT_EQ(seg.model_class_count(), 80);
  int found = 0;
  for (int i = 1; i <= 10; ++i) {
    const auto stem = root / "data/0000" / cv::format("%06d", i);
    const cv::Mat rgb = cv::imread(stem.string() + "-color.png", cv::IMREAD_COLOR);
    const cv::Mat raw_label = cv::imread(stem.string() + "-label.png", cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(rgb.empty());
    ASSERT_FALSE(raw_label.empty());
    const cv::Mat mug = raw_label == 14;  // YCB-Video 025_mug
    const SegmentationResult r = seg.segment_image(rgb);
    const double iou = best_iou(r, id(Label::kCup), mug);
    std::printf("ycb frame %d: %zu instances, mug-as-cup mask IoU %.3f\n", i, r.instances.size(), iou);
    found += iou >= 0.5;
    // Instances are consistent with the painted images.
    for (const auto& inst : r.instances) {
      EXPECT_EQ(inst.mask.size(), rgb.size());
      EXPECT_EQ(inst.class_scores.size(), size_t(kNumClasses));
      EXPECT_GT(inst.score, 0.f);
    }
  }
  std::printf("ycb mug found as cup (mask IoU >= 0.5) on %d of 10 frames\n", found);
  EXPECT_GE(found, 8);
}

TEST(YoloSegmenter, FindsChairAndTableIn7Scenes) {
  SEMAP_REQUIRE_DATA(root, "7scenes_redkitchen");
  REQUIRE_MODEL(path, "yolov8n-seg-320.onnx");
  SegmentationConfig config;
  YoloSegmenter seg(path, config);
  int chair_frames = 0, table_frames = 0;
  for (int i : {0, 200, 400}) {
    const cv::Mat rgb = cv::imread((root / cv::format("frame-%06d.color.jpg", i)).string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(rgb.empty());
    const SegmentationResult r = seg.segment_image(rgb);
    bool chair = false, table = false;
    std::printf("7scenes frame %d:", i);
    for (const auto& inst : r.instances) {
      std::printf(" %s %.2f", std::string(class_name(inst.class_id)).c_str(), inst.score);
      chair |= inst.class_id == id(Label::kChair);
      table |= inst.class_id == id(Label::kTable);
    }
    std::printf("\n");
    chair_frames += chair;
    table_frames += table;
  }
  std::printf("7scenes: chair on %d/3 frames, table on %d/3 frames\n", chair_frames, table_frames);
  EXPECT_GE(chair_frames, 2);
  EXPECT_GE(table_frames, 2);
}

TEST(SemanticSegmenter, DeeplabGivesPlausibleVocClasses) {
  SEMAP_REQUIRE_DATA(root, "7scenes_redkitchen");
  REQUIRE_MODEL(path, "deeplabv3-mnv2-voc-257.onnx");
  SegmentationConfig config;
  SemanticSegmenter seg(path, config);
  EXPECT_TRUE(seg.input_is_nhwc());
  EXPECT_EQ(seg.input_size(), cv::Size(257, 257));
  const cv::Mat rgb = cv::imread((root / "frame-000000.color.jpg").string(), cv::IMREAD_COLOR);
  const SegmentationResult r = seg.segment_image(rgb);
  ASSERT_EQ(r.labels.size(), rgb.size());
  ASSERT_EQ(r.probabilities.channels(), kNumClasses);
  std::array<int, kNumClasses> hist{};
  for (int y = 0; y < r.labels.rows; ++y)
    for (int x = 0; x < r.labels.cols; ++x) ++hist[r.labels.at<uint8_t>(y, x)];
  std::printf("deeplab 7scenes frame 0 label fractions:");
  for (int c = 0; c < kNumClasses; ++c)
    if (hist[c]) std::printf(" %s %.3f", std::string(class_name(ClassId(c))).c_str(), double(hist[c]) / rgb.total());
  std::printf("\n");
  // Plausible for a kitchen with table and chairs: indoor VOC classes dominate the labelled
  // pixels; outdoor/animal VOC classes map to "other" and must stay a minority.
  const int labelled = int(rgb.total()) - hist[0];
  const int indoor = hist[id(Label::kChair)] + hist[id(Label::kTable)] + hist[id(Label::kSofa)] +
                     hist[id(Label::kMonitor)] + hist[id(Label::kBottle)] + hist[id(Label::kPlant)] +
                     hist[id(Label::kPerson)];
  EXPECT_GT(hist[id(Label::kChair)] + hist[id(Label::kTable)], 0.02 * rgb.total());
  EXPECT_GT(indoor, hist[id(Label::kOther)]);
  EXPECT_GT(labelled, 0);
  // Probabilities are distributions and agree with the labels.
  const cv::Vec<float, 1>* unused = nullptr;
  (void)unused;
  for (int y = 0; y < rgb.rows; y += 37)
    for (int x = 0; x < rgb.cols; x += 41) {
      const float* p = r.probabilities.ptr<float>(y) + size_t(x) * kNumClasses;
      float sum = 0;
      int best = 0;
      for (int c = 0; c < kNumClasses; ++c) {
        sum += p[c];
        if (p[c] > p[best]) best = c;
      }
      EXPECT_NEAR(sum, 1.f, 1e-3);
      EXPECT_EQ(best, r.labels.at<uint8_t>(y, x));
    }
}

TEST(SegmenterFactory, SpecsAndErrors) {
  SegmentationConfig config;
  CameraModel camera;
  EXPECT_EQ(make_segmenter("none", config, camera), nullptr);
  EXPECT_EQ(make_segmenter("groundtruth", config, camera)->name(), "groundtruth");
  EXPECT_THROW(make_segmenter("bogus", config, camera), Error);
  try {
    make_segmenter("yolo:/nonexistent/model.onnx", config, camera);
    FAIL() << "no error for a missing model";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/model.onnx"), std::string::npos) << e.what();
  }
  test::TempDir dir;
  test::write_text(dir / "corrupt.onnx", "this is not a protobuf \x01\x02\x03 at all");
  try {
    make_segmenter("yolo:" + (dir / "corrupt.onnx").string(), config, camera);
    FAIL() << "no error for a corrupt model";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("corrupt.onnx"), std::string::npos) << e.what();
  }
  // Truncated real model.
  const auto real = model("yolov8n-seg-320.onnx");
  if (std::filesystem::exists(real)) {
    std::ifstream in(real, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    test::write_text(dir / "truncated.onnx", bytes.substr(0, bytes.size() / 3));
    EXPECT_THROW(make_segmenter("yolo:" + (dir / "truncated.onnx").string(), config, camera), Error);
    // Wrong kind: the semantic model given as yolo.
    const auto deeplab = model("deeplabv3-mnv2-voc-257.onnx");
    try {
      make_segmenter("yolo:" + deeplab.string(), config, camera);
      FAIL() << "semantic model accepted as YOLO";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("deeplabv3"), std::string::npos) << e.what();
    }
    // Kind detection from the graph.
    EXPECT_EQ(make_segmenter(real.string(), config, camera)->name(), "yolo:" + real.string());
    EXPECT_EQ(make_segmenter(deeplab.string(), config, camera)->name(), "semantic:" + deeplab.string());
  }
}

}  // namespace
}  // namespace semap

namespace semap {
namespace {

// The decoder takes the anchor count, prototype grid, class count and layout from the
// tensors: a 640 export ([1,116,8400] + [1,32,160,160]) decodes with the same code. (The
// shared 320 file has fixed shapes inside its graph, so it cannot itself run at 640.)
void check_640_decode(bool transposed) {
  REQUIRE_MODEL(path, "yolov8n-seg-320.onnx");
  YoloSegmenter seg(path, SegmentationConfig{});
  const int n = 8400, nc = 80, nm = 32, channels = 4 + nc + nm;
  const int det_dims[3] = {1, transposed ? n : channels, transposed ? channels : n};
  cv::Mat det(3, det_dims, CV_32F, cv::Scalar(0));
  auto at = [&](int ch, int anchor) -> float& {
    return transposed ? det.ptr<float>()[size_t(anchor) * channels + ch] : det.ptr<float>()[size_t(ch) * n + anchor];
  };
  // One cup (COCO 41) box centred at (320, 300) input px, 200 x 160; prototype 0 is +8 in a
  // disc around the box centre and -8 elsewhere; coefficient 0 = 1.
  const int anchor = 1234;
  at(0, anchor) = 320, at(1, anchor) = 300, at(2, anchor) = 200, at(3, anchor) = 160;
  at(4 + 41, anchor) = 0.9f;
  at(4 + nc + 0, anchor) = 1.f;
  const int proto_dims[4] = {1, nm, 160, 160};
  cv::Mat proto(4, proto_dims, CV_32F, cv::Scalar(0));
  cv::Mat p0(160, 160, CV_32F, proto.ptr<float>());
  p0.setTo(-8.f);
  cv::circle(p0, cv::Point(80, 75), 30, cv::Scalar(8.f), cv::FILLED);  // input (320, 300), radius 120 px
  // 640x480 image letterboxed into 640x640: scale 1, pad_y 80.
  Letterbox lb;
  lb.input = {640, 640};
  lb.scale = 1.0;
  lb.pad_x = 0;
  lb.pad_y = 80;
  const auto cand = seg.candidates_from_outputs(det, proto, lb, cv::Size(640, 480));
  ASSERT_EQ(cand.boxes.size(), 1u);
  EXPECT_EQ(cand.proto_size, cv::Size(160, 160));
  EXPECT_NEAR(cand.boxes[0].box.x, 220, 1e-3);
  EXPECT_NEAR(cand.boxes[0].box.y, 140, 1e-3);  // 300 - 80 - 80
  const SegmentationResult r = seg.decode(cand);
  ASSERT_EQ(r.instances.size(), 1u);
  EXPECT_EQ(r.instances[0].class_id, id(Label::kCup));
  // Expected mask: the disc (centre (320, 220) image px, radius 120) cropped to the box.
  cv::Mat expected = cv::Mat::zeros(480, 640, CV_8UC1);
  cv::circle(expected, cv::Point(320, 220), 120, cv::Scalar(255), cv::FILLED);
  cv::Mat box_mask = cv::Mat::zeros(480, 640, CV_8UC1);
  box_mask(cv::Rect(220, 140, 200, 160)).setTo(255);
  expected &= box_mask;
  EXPECT_GT(mask_iou(r.instances[0].mask, expected), 0.97);
  EXPECT_EQ(r.instances[0].box, cv::Rect(220, 140, 200, 160));
}

TEST(YoloSegmenter, Decodes640LayoutFromTensorShapes) { check_640_decode(false); }
TEST(YoloSegmenter, DecodesTransposedDetectionLayout) { check_640_decode(true); }

}  // namespace
}  // namespace semap
