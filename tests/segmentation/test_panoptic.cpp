// Panoptic segmentation from two networks (issue 38): the per-pixel combination rule on
// synthetic results, the ADE20K class mapping and the new project classes.
#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <set>

#include "semap/core/error.hpp"
#include "semap/segmentation/segmenter_factory.hpp"
#include "segmentation/class_mapping.hpp"
#include "segmentation/panoptic_segmenter.hpp"
#include "segmentation/segmentation_utils.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

constexpr int kW = 40, kH = 20;

/// Left half wall, right half floor, a semantic "chair" blob no instance covers, one
/// unlabelled strip; confidence 0.8 and matching probabilities.
SegmentationResult semantic_result() {
  SegmentationResult r;
  r.labels = cv::Mat(kH, kW, CV_8UC1, cv::Scalar(id(Label::kWall)));
  r.labels(cv::Rect(kW / 2, 0, kW / 2, kH)).setTo(id(Label::kFloor));
  r.labels(cv::Rect(30, 2, 4, 4)).setTo(id(Label::kChair));
  r.labels(cv::Rect(0, kH - 2, kW, 2)).setTo(0);
  r.confidence = cv::Mat(kH, kW, CV_32FC1, cv::Scalar(0.8f));
  r.probabilities = cv::Mat(kH, kW, CV_32FC(kNumClasses), cv::Scalar::all(0));
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) r.probabilities.ptr<float>(y)[x * kNumClasses + r.labels.at<uint8_t>(y, x)] = 0.8f;
  return r;
}

InstanceDetection instance(uint16_t iid, Label c, float score, cv::Rect box) {
  InstanceDetection d;
  d.id = iid, d.class_id = id(c), d.score = score, d.box = box;
  d.mask = cv::Mat::zeros(kH, kW, CV_8UC1);
  d.mask(box).setTo(255);
  return d;
}

/// A table over wall and floor, a cup overlapping it (higher score: on top), and a monitor
/// reaching into the unlabelled strip.
SegmentationResult instance_result(bool painted) {
  SegmentationResult r;
  r.instances = {instance(1, Label::kTable, 0.6f, {10, 5, 20, 8}), instance(2, Label::kCup, 0.9f, {12, 6, 4, 4}),
                 instance(3, Label::kMonitor, 0.7f, {2, 15, 5, 5})};
  if (painted) paint_instances(r, {kW, kH});
  return r;
}

/// A deep copy: combine_panoptic() writes into the semantic images it is given.
SegmentationResult clone(const SegmentationResult& r) {
  SegmentationResult c = r;
  c.labels = r.labels.clone(), c.confidence = r.confidence.clone(), c.probabilities = r.probabilities.clone();
  c.instance_ids = r.instance_ids.clone();
  return c;
}

int argmax(const cv::Mat& probs, int y, int x) {
  const float* p = probs.ptr<float>(y) + size_t(x) * kNumClasses;
  return int(std::max_element(p, p + kNumClasses) - p);
}

void check_rule(const SegmentationResult& sem, const SegmentationResult& inst, const SegmentationResult& out) {
  ASSERT_EQ(out.labels.size(), sem.labels.size());
  ASSERT_EQ(out.instance_ids.type(), CV_16UC1);
  ASSERT_EQ(out.instances.size(), inst.instances.size());
  int inside = 0, outside = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const uint16_t iid = out.instance_ids.at<uint16_t>(y, x);
      const uint8_t label = out.labels.at<uint8_t>(y, x);
      // The winner at a pixel: the highest-scoring mask covering it.
      const InstanceDetection* best = nullptr;
      for (const auto& d : inst.instances)
        if (d.mask.at<uint8_t>(y, x) && (!best || d.score > best->score)) best = &d;
      if (best) {
        ++inside;
        ASSERT_EQ(iid, best->id) << x << "," << y;
        ASSERT_EQ(label, best->class_id) << x << "," << y;
        EXPECT_FLOAT_EQ(out.confidence.at<float>(y, x), best->score);
        EXPECT_EQ(argmax(out.probabilities, y, x), best->class_id);
      } else {
        ++outside;
        ASSERT_EQ(iid, 0) << x << "," << y;
        ASSERT_EQ(label, sem.labels.at<uint8_t>(y, x)) << x << "," << y;
        EXPECT_FLOAT_EQ(out.confidence.at<float>(y, x), sem.confidence.at<float>(y, x));
        if (label != 0) EXPECT_EQ(argmax(out.probabilities, y, x), label);
      }
    }
  EXPECT_GT(inside, 100);
  EXPECT_GT(outside, 300);
}

TEST(Panoptic, InstanceWinsInsideSemanticFillsTheRest) {
  const SegmentationResult sem = semantic_result();
  for (bool painted : {true, false}) {  // instance ids painted by the YOLO segmenter, or here
    SCOPED_TRACE(painted);
    const SegmentationResult inst = instance_result(painted);
    const SegmentationResult out = combine_panoptic(clone(sem), inst);
    check_rule(sem, inst, out);
    // The semantic chair no instance covers keeps its label, without an instance id; the
    // unlabelled strip stays 0 outside the monitor.
    EXPECT_EQ(out.labels.at<uint8_t>(3, 31), id(Label::kChair));
    EXPECT_EQ(out.instance_ids.at<uint16_t>(3, 31), 0);
    EXPECT_EQ(out.labels.at<uint8_t>(kH - 1, 20), 0);
    EXPECT_EQ(out.labels.at<uint8_t>(kH - 1, 3), id(Label::kMonitor));
  }
}

TEST(Panoptic, InstanceProbabilitiesAreALabelObservation) {
  const SegmentationResult out = combine_panoptic(semantic_result(), instance_result(true));
  const float* p = out.probabilities.ptr<float>(7) + size_t(13) * kNumClasses;  // inside the cup
  double sum = 0;
  for (int c = 0; c < kNumClasses; ++c) sum += p[c];
  EXPECT_NEAR(sum, 1.0, 1e-4);
  EXPECT_FLOAT_EQ(p[id(Label::kCup)], 0.9f);
  EXPECT_EQ(p[0], 0.f);
  EXPECT_NEAR(p[id(Label::kWall)], 0.1 / (kNumClasses - 2), 1e-6);
}

TEST(Panoptic, WeakInstancesOnlyFeedTheObjectMap) {
  const SegmentationResult sem = semantic_result();
  const SegmentationResult out = combine_panoptic(clone(sem), instance_result(true), 0.65);  // table scores 0.6
  EXPECT_EQ(out.instances.size(), 3u);
  EXPECT_EQ(out.labels.at<uint8_t>(11, 25), sem.labels.at<uint8_t>(11, 25));  // table pixel: semantic kept
  EXPECT_EQ(out.instance_ids.at<uint16_t>(11, 25), 0);
  EXPECT_EQ(out.labels.at<uint8_t>(7, 13), id(Label::kCup));
  EXPECT_EQ(out.instance_ids.at<uint16_t>(7, 13), 2);
  EXPECT_EQ(out.labels.at<uint8_t>(16, 3), id(Label::kMonitor));
}

TEST(Panoptic, EitherSideMayBeEmpty) {
  // No instances: the semantic result unchanged.
  const SegmentationResult sem = semantic_result();
  const SegmentationResult only_sem = combine_panoptic(clone(sem), SegmentationResult{});
  EXPECT_EQ(cv::countNonZero(only_sem.labels != sem.labels), 0);
  // No semantic labels (e.g. its confidence floor removed all): instances alone, no confidence.
  const SegmentationResult only_inst = combine_panoptic(SegmentationResult{}, instance_result(false));
  ASSERT_EQ(only_inst.labels.size(), cv::Size(kW, kH));
  EXPECT_EQ(only_inst.labels.at<uint8_t>(6, 11), id(Label::kTable));
  EXPECT_EQ(only_inst.labels.at<uint8_t>(0, 0), 0);
  EXPECT_TRUE(only_inst.confidence.empty());
}

TEST(Panoptic, SizeMismatchIsAnError) {
  SegmentationResult inst = instance_result(true);
  cv::resize(inst.instance_ids, inst.instance_ids, {kW / 2, kH / 2}, 0, 0, cv::INTER_NEAREST);
  EXPECT_THROW(combine_panoptic(semantic_result(), inst), Error);
}

/// A segmenter returning a fixed result.
class FixedSegmenter : public Segmenter {
 public:
  FixedSegmenter(SegmentationResult r, std::string name) : r_(std::move(r)), name_(std::move(name)) {}
  SegmentationResult segment(const Frame&) override { return r_; }
  std::string name() const override { return name_; }

 private:
  SegmentationResult r_;
  std::string name_;
};

TEST(Panoptic, SegmenterComposesTwoSegmenters) {
  PanopticSegmenter seg(std::make_unique<FixedSegmenter>(semantic_result(), "semantic:a.onnx"),
                        std::make_unique<FixedSegmenter>(instance_result(true), "yolo:b.onnx"));
  EXPECT_EQ(seg.name(), "panoptic:semantic:a.onnx+yolo:b.onnx");
  Frame frame;
  frame.index = 7;
  const SegmentationResult out = seg.segment(frame);
  EXPECT_EQ(out.frame_index, 7u);
  check_rule(semantic_result(), instance_result(true), out);
  EXPECT_GE(seg.last_timing().combine_ms, 0.0);
  EXPECT_THROW(PanopticSegmenter(nullptr, std::make_unique<FixedSegmenter>(SegmentationResult{}, "x")), Error);
}

TEST(Panoptic, SpecErrorsNameTheModel) {
  const CameraModel camera;
  try {
    make_segmenter("panoptic:/nonexistent/sem.onnx+/nonexistent/inst.onnx", SegmentationConfig{}, camera);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("sem.onnx"), std::string::npos) << e.what();
  }
  EXPECT_THROW(make_segmenter("panoptic:/only/one.onnx", SegmentationConfig{}, camera), Error);
  EXPECT_EQ(make_segmenter("default", SegmentationConfig{}, camera), nullptr);  // resolved by run drivers only
}

// ---- classes ----

TEST(PanopticClasses, Ade20kNamesMapToProjectClasses) {
  const ClassMapping ade(ade20k32_class_names());
  ASSERT_EQ(ade.size(), 32u);
  const std::vector<std::pair<std::string, Label>> expected = {
      {"other", Label::kOther},     {"wall", Label::kWall},       {"floor", Label::kFloor},
      {"ceiling", Label::kCeiling}, {"bed", Label::kBed},         {"windowpane", Label::kWindow},
      {"cabinet", Label::kCabinet}, {"person", Label::kPerson},   {"door", Label::kDoor},
      {"table", Label::kTable},     {"plant", Label::kPlant},     {"curtain", Label::kCurtain},
      {"chair", Label::kChair},     {"painting", Label::kPicture}, {"sofa", Label::kSofa},
      {"shelf", Label::kShelf},     {"mirror", Label::kMirror},   {"rug", Label::kRug},
      {"armchair", Label::kChair},  {"sky", Label::kOther},       {"car", Label::kOther}};
  for (const auto& [name, label] : expected) {
    const auto& names = ade.model_names();
    const auto it = std::find(names.begin(), names.end(), name);
    ASSERT_NE(it, names.end()) << name;
    EXPECT_EQ(class_name(ade.map(int(it - names.begin()))), class_name(id(label))) << name;
  }
  EXPECT_EQ(map_class_name("carpet"), id(Label::kRug));
  EXPECT_EQ(map_class_name("drapes"), id(Label::kCurtain));
  EXPECT_EQ(map_class_name("picture frame"), id(Label::kPicture));
  // A 32-class model without a names file gets the built-in ADE20K list; a network's own file wins.
  SegmentationConfig config;
  EXPECT_EQ(make_class_mapping(config, 32, "m.onnx").map(9), id(Label::kWindow));
  config.class_names_file = "/nonexistent/shared.txt";
  config.semantic.class_names_file = "/nonexistent/semantic.txt";
  try {
    make_class_mapping(config, 32, "m.onnx", config.semantic.class_names_file);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("semantic.txt"), std::string::npos) << e.what();
  }
}

TEST(PanopticClasses, NewClassesAppendedWithOwnColours) {
  // Ids stored in saved maps keep their values: the new classes come after "other".
  EXPECT_EQ(int(id(Label::kOther)), 38);
  const std::vector<Label> added = {Label::kCurtain, Label::kPicture, Label::kRug, Label::kMirror};
  std::set<std::string> names;
  for (Label l : added) {
    EXPECT_GT(id(l), id(Label::kOther));
    EXPECT_LT(int(id(l)), kNumClasses);
    EXPECT_EQ(class_from_name(class_name(id(l))), id(l));
    names.insert(std::string(class_name(id(l))));
    for (int c = 0; c < kNumClasses; ++c)
      if (c != id(l)) EXPECT_FALSE(class_colour(ClassId(c)) == class_colour(id(l))) << class_name(id(l)) << " vs " << class_name(ClassId(c));
  }
  EXPECT_EQ(names, (std::set<std::string>{"curtain", "picture", "rug", "mirror"}));
  EXPECT_TRUE(is_stuff(id(Label::kCurtain)));
  EXPECT_TRUE(is_stuff(id(Label::kRug)));
  EXPECT_TRUE(is_stuff(id(Label::kMirror)));
  EXPECT_FALSE(is_stuff(id(Label::kPicture)));
  EXPECT_FALSE(is_stuff(id(Label::kOther)));
}

}  // namespace
}  // namespace semap
