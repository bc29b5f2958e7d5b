// Precomputed segmentation JSON (NAME.json beside NAME.label.png / NAME.instances.png, as
// `semap segment` writes and `--segmenter precomputed:DIR` reads): PrecomputedSegmenter::read
// with fixed small label and instance images.
#include <opencv2/core.hpp>

#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "io/image_io.hpp"
#include "segmentation/groundtruth_segmenter.hpp"
#include "segmentation/segmentation_io.hpp"

namespace {

const std::filesystem::path& seg_dir() {
  static const std::filesystem::path dir = [] {
    auto d = semap::fuzz::scratch_dir() / "seg";
    std::filesystem::create_directories(d);
    cv::Mat labels(8, 8, CV_16UC1, cv::Scalar(0)), instances(8, 8, CV_16UC1, cv::Scalar(0));
    labels(cv::Rect(1, 1, 3, 3)).setTo(20);
    instances(cv::Rect(1, 1, 3, 3)).setTo(1);
    labels(cv::Rect(4, 4, 3, 2)).setTo(7);
    instances(cv::Rect(4, 4, 3, 2)).setTo(2);
    semap::write_image(d / "f.label.png", labels);
    semap::write_image(d / "f.instances.png", instances);
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  semap::SegmentationResult r;
  r.labels = cv::Mat(8, 8, CV_8UC1, cv::Scalar(0));
  r.instance_ids = cv::Mat(8, 8, CV_16UC1, cv::Scalar(0));
  semap::InstanceDetection inst;
  inst.id = 1;
  inst.class_id = 20;
  inst.score = 0.9f;
  inst.box = cv::Rect(1, 1, 3, 3);
  inst.class_scores.assign(semap::kNumClasses, 0.f);
  inst.class_scores[20] = 0.9f;
  inst.class_scores[22] = 0.1f;
  r.instances.push_back(inst);
  semap::fuzz::write_seed("seg.json", semap::segmentation_to_json(r, "f.png", {8, 8}, "yolo:fuzz").dump(2));
  semap::fuzz::write_seed("external.json", R"({"label_names": ["bg", "chair", "cup"], "instances": [)"
                                           R"({"id": 2, "class": "chair"}, {"id": 1, "class_id": 20, "score": 0.5}]})");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  semap::fuzz::write_bytes(seg_dir() / "f.json", data, size);
  try {
    semap::PrecomputedSegmenter(seg_dir(), semap::SegmentationConfig{}).read("f");
  } catch (const semap::Error&) {
  }
  return 0;
}
