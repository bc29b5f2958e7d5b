// Panoptic segmentation on real kitchen frames (issue 38): the ADE20K semantic model and a COCO
// instance model together label most of what the depth camera sees; instance pixels keep their
// instance's class. Prints per-network times and the labelled share per class group.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>

#include "semap/pipeline/run_pipeline.hpp"
#include "segmentation/panoptic_segmenter.hpp"
#include "segmentation/semantic_segmenter.hpp"
#include "segmentation/yolo_segmenter.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

enum Group { kStructure, kFurniture, kCovering, kObject, kOtherGroup, kGroups };
constexpr const char* kGroupNames[kGroups] = {"structure", "furniture", "covering", "object", "other"};

Group group_of(ClassId c) {
  if (c >= id(Label::kWall) && c <= id(Label::kWindow)) return kStructure;
  if (c >= id(Label::kTable) && c <= id(Label::kDesk)) return kFurniture;
  if (c > id(Label::kOther)) return kCovering;  // curtain, picture, rug, mirror
  if (c == id(Label::kOther)) return kOtherGroup;
  return kObject;
}

/// "Named": a project class other than unlabelled/other (the semantic argmax names some class
/// at every pixel, so this checks the mapping and the models, not the coverage rule).
/// "Confident": named with confidence >= kMinConfidence (instance pixels: the instance score).
constexpr float kMinConfidence = 0.5f;

struct Shares {
  double named = 0, labelled = 0, semantic_labelled = 0, instance = 0;
  double group[kGroups] = {};
};

/// Shares of the valid-depth pixels (7-Scenes: 0 and 65535 are invalid; colour and depth are
/// the same size and near enough aligned for a share).
Shares shares(const SegmentationResult& sem, const SegmentationResult& out, const cv::Mat& depth) {
  Shares s;
  double valid = 0;
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) {
      const uint16_t d = depth.at<uint16_t>(y, x);
      if (d == 0 || d == 65535) continue;
      ++valid;
      const uint8_t label = out.labels.at<uint8_t>(y, x);
      s.named += label != 0 && label != id(Label::kOther);
      s.semantic_labelled += sem.labels.at<uint8_t>(y, x) != 0 && sem.confidence.at<float>(y, x) >= kMinConfidence;
      s.instance += out.instance_ids.empty() ? 0 : out.instance_ids.at<uint16_t>(y, x) != 0;
      if (label == 0 || out.confidence.at<float>(y, x) < kMinConfidence) continue;
      ++s.labelled;
      s.group[group_of(label)] += 1;
    }
  for (double* v : {&s.named, &s.labelled, &s.semantic_labelled, &s.instance}) *v /= valid;
  for (double& g : s.group) g /= valid;
  return s;
}

/// Every instance pixel carries its instance's class.
void expect_instance_pixels_consistent(const SegmentationResult& out) {
  std::vector<int> class_of(65536, -1);
  for (const auto& d : out.instances) class_of[d.id] = d.class_id;
  int wrong = 0;
  for (int y = 0; y < out.labels.rows; ++y)
    for (int x = 0; x < out.labels.cols; ++x) {
      const uint16_t i = out.instance_ids.empty() ? 0 : out.instance_ids.at<uint16_t>(y, x);
      if (i != 0) wrong += class_of[i] != out.labels.at<uint8_t>(y, x);
    }
  EXPECT_EQ(wrong, 0);
}

TEST(PanopticReal, LabelsMostOfAKitchen) {
  SEMAP_REQUIRE_DATA(root, "7scenes_redkitchen");
  SEMAP_REQUIRE_MODEL(semantic_path, kDefaultSemanticModel);
  SegmentationConfig config;
  SemanticSegmenter semantic(semantic_path, config);
  for (const char* instance_name : kDefaultInstanceModels) {
    SEMAP_REQUIRE_MODEL(instance_path, instance_name);
    YoloSegmenter instance(instance_path, config);
    double sem_ms = 0, inst_ms = 0, comb_ms = 0, min_labelled = 1, sum_labelled = 0;
    const std::vector<int> frames = {0, 150, 300, 450};
    for (int i : frames) {
      const cv::Mat rgb = cv::imread((root / cv::format("frame-%06d.color.jpg", i)).string(), cv::IMREAD_COLOR);
      const cv::Mat depth = cv::imread((root / cv::format("frame-%06d.depth.png", i)).string(), cv::IMREAD_UNCHANGED);
      ASSERT_FALSE(rgb.empty() || depth.empty());
      ASSERT_EQ(depth.size(), rgb.size());
      auto t0 = Clock::now();
      const SegmentationResult sem = semantic.segment_image(rgb);
      sem_ms += ms_since(t0);
      t0 = Clock::now();
      const SegmentationResult inst = instance.segment_image(rgb);
      inst_ms += ms_since(t0);
      SegmentationResult sem_copy = sem;
      sem_copy.labels = sem.labels.clone(), sem_copy.confidence = sem.confidence.clone();
      sem_copy.probabilities = sem.probabilities.clone();
      t0 = Clock::now();
      const SegmentationResult out = combine_panoptic(std::move(sem_copy), inst, config.panoptic.min_instance_score);
      comb_ms += ms_since(t0);
      expect_instance_pixels_consistent(out);
      const Shares s = shares(sem, out, depth);
      std::printf("%s frame %d: named %.3f, confident %.3f (semantic alone %.3f), instance %.3f; %zu instances;",
                  instance_name, i, s.named, s.labelled, s.semantic_labelled, s.instance, inst.instances.size());
      for (int g = 0; g < kGroups; ++g) std::printf(" %s %.3f", kGroupNames[g], s.group[g]);
      std::printf("\n");
      EXPECT_LE(s.instance, s.labelled);  // kept instance pixels (score >= 0.5) are a subset of the confident ones
      EXPECT_GE(s.labelled, s.semantic_labelled);  // the instances only add confident pixels
      EXPECT_GT(s.group[kStructure], 0.2);  // walls, floor, cabinets are labelled now
      EXPECT_GE(s.named, 0.85);
      min_labelled = std::min(min_labelled, s.labelled);
      sum_labelled += s.labelled;
    }
    const double n = double(frames.size());
    std::printf("%s: per frame semantic %.0f ms, instance %.0f ms, combination %.1f ms; confident mean %.3f min %.3f\n",
                instance_name, sem_ms / n, inst_ms / n, comb_ms / n, sum_labelled / n, min_labelled);
    EXPECT_GE(sum_labelled / n, 0.5);
  }
}

}  // namespace
}  // namespace semap
