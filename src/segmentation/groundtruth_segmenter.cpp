#include "segmentation/groundtruth_segmenter.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "io/image_io.hpp"
#include "io/json_number.hpp"
#include "segmentation/class_mapping.hpp"
#include "segmentation/segmentation_utils.hpp"
#include "core/json_text.hpp"

namespace semap {


SegmentationResult result_from_label_images(const cv::Mat& labels, const cv::Mat& instances, const std::string& where) {
  CV_Assert(labels.type() == CV_8UC1);
  SegmentationResult r;
  r.labels = labels.clone();
  if (!instances.empty()) {
    CV_Assert(instances.type() == CV_16UC1 && instances.size() == labels.size());
    r.instance_ids = instances.clone();
    // Per instance id: label histogram and bounding box in one pass.
    std::map<uint16_t, std::array<int, kNumClasses>> hist;
    for (int y = 0; y < labels.rows; ++y) {
      const uint16_t* ins = instances.ptr<uint16_t>(y);
      const uint8_t* lab = labels.ptr<uint8_t>(y);
      for (int x = 0; x < labels.cols; ++x)
        if (ins[x]) {
          auto [it, fresh] = hist.try_emplace(ins[x]);
          if (fresh) it->second.fill(0);
          ++it->second[std::min<int>(lab[x], kNumClasses - 1)];
        }
    }
    check_instance_count(hist.size(), labels.size(), where);  // before a mask per instance
    for (auto& [iid, h] : hist) {
      // Majority label, ignoring unlabelled when any label exists.
      int best = 0;
      for (int c = 1; c < kNumClasses; ++c)
        if (h[c] > h[best] || (best == 0 && h[c] > 0)) best = c;
      InstanceDetection inst;
      inst.id = iid;
      inst.class_id = ClassId(best);
      inst.score = 1.f;
      inst.class_scores = one_hot_scores(inst.class_id);
      inst.mask = instances == iid;
      inst.box = cv::boundingRect(inst.mask);
      r.instances.push_back(std::move(inst));
    }
  } else {
    r.instance_ids = cv::Mat::zeros(labels.size(), CV_16UC1);
    uint16_t next = 1;
    for (int c = 1; c < kNumClasses; ++c) {
      if (is_stuff(ClassId(c))) continue;
      cv::Mat mask = labels == c;
      if (cv::countNonZero(mask) == 0) continue;
      InstanceDetection inst;
      inst.id = next++;
      inst.class_id = ClassId(c);
      inst.score = 1.f;
      inst.class_scores = one_hot_scores(inst.class_id);
      inst.box = cv::boundingRect(mask);
      r.instance_ids.setTo(inst.id, mask);
      inst.mask = std::move(mask);
      r.instances.push_back(std::move(inst));
    }
  }
  return r;
}

SegmentationResult GroundTruthSegmenter::segment(const Frame& frame) {
  if (!frame.has_labels())
    throw Error(frame.rgb_path.empty() ? std::string("groundtruth segmenter") : frame.rgb_path,
                "frame has no ground-truth labels (use a synthetic or YCB-Video dataset, or precomputed:DIR)");
  SegmentationResult r = result_from_label_images(frame.labels, frame.instances, frame.rgb_path.empty() ? "ground-truth instances" : frame.rgb_path);
  r.frame_index = frame.index;
  r.timestamp = frame.timestamp;
  return r;
}

PrecomputedSegmenter::PrecomputedSegmenter(const std::filesystem::path& dir, const SegmentationConfig& config)
    : dir_(dir), config_(config) {
  if (!std::filesystem::is_directory(dir)) throw Error(dir, "precomputed segmentation folder not found");
}

SegmentationResult PrecomputedSegmenter::segment(const Frame& frame) {
  if (frame.rgb_path.empty()) throw Error(dir_, "precomputed segmenter needs the frame's rgb file name");
  SegmentationResult r = read(std::filesystem::path(frame.rgb_path).stem().string());
  r.frame_index = frame.index;
  r.timestamp = frame.timestamp;
  return r;
}

SegmentationResult PrecomputedSegmenter::read(const std::string& name) const {
  const auto json_path = dir_ / (name + ".json");
  const auto label_path = dir_ / (name + ".label.png");
  const auto inst_path = dir_ / (name + ".instances.png");
  nlohmann::json j;
  {
    const std::string text = read_regular_file(json_path, kMaxTextFileBytes, "precomputed segmentation");
    try {
      j = nlohmann::json::parse(text);
    } catch (const std::exception& e) {
      throw Error(json_path, std::string("malformed JSON: ") + e.what());
    }
  }
  cv::Mat label16 = read_label_image(label_path);
  cv::Mat inst16 = std::filesystem::exists(inst_path) ? read_label_image(inst_path, label16.size()) : cv::Mat();

  // Label values -> project ids: the tool's own list (by name) or project ids already.
  std::vector<ClassId> lut;
  if (j.contains("label_names")) {
    if (!j["label_names"].is_array()) throw Error(json_path, "label_names must be an array of names");
    for (const auto& n : j["label_names"]) lut.push_back(map_class_name(n.is_string() ? n.get<std::string>() : ""));
  }
  cv::Mat labels(label16.size(), CV_8UC1);
  for (int y = 0; y < labels.rows; ++y) {
    const uint16_t* s = label16.ptr<uint16_t>(y);
    uint8_t* d = labels.ptr<uint8_t>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (!lut.empty()) d[x] = s[x] < lut.size() ? lut[s[x]] : id(Label::kOther);
      else d[x] = s[x] < kNumClasses ? ClassId(s[x]) : id(Label::kOther);
    }
  }
  SegmentationResult r;
  r.labels = labels;
  if (!inst16.empty()) r.instance_ids = inst16;
  if (!j.contains("instances")) return result_from_label_images(labels, inst16, inst_path.string());
  if (j.at("instances").is_array()) check_instance_count(j.at("instances").size(), labels.size(), json_path.string());
  try {
    for (const auto& ji : j.at("instances")) {
      InstanceDetection inst;
      inst.id = static_cast<uint16_t>(json_number(ji.at("id"), "id", 0, 65535, true));
      if (ji.contains("class")) inst.class_id = map_class_name(ji.at("class").get<std::string>());
      else {
        const int c = static_cast<int>(json_number(ji.at("class_id"), "class_id", -1e9, 1e9, true));
        inst.class_id = c >= 0 && c < kNumClasses ? ClassId(c) : id(Label::kOther);
      }
      inst.score = ji.contains("score") ? static_cast<float>(json_number(ji["score"], "score", 0, 1e6, false)) : 1.f;
      if (ji.contains("class_scores") && ji["class_scores"].is_object()) {
        inst.class_scores.assign(kNumClasses, 0.f);
        for (const auto& [k, v] : ji["class_scores"].items()) {
          const ClassId c = map_class_name(k);
          inst.class_scores[c] = std::max(inst.class_scores[c], static_cast<float>(json_number(v, "class_scores", 0, 1e6, false)));
        }
      }
      if (inst16.empty()) throw Error(inst_path, "instances listed in the JSON but the instance image is missing");
      inst.mask = inst16 == inst.id;
      if (cv::countNonZero(inst.mask) == 0) continue;  // e.g. fully occluded by another mask
      inst.box = cv::boundingRect(inst.mask);
      r.instances.push_back(std::move(inst));
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(json_path, "bad instance entry: " + json_error_text(e));
  }
  return r;
}

}  // namespace semap
