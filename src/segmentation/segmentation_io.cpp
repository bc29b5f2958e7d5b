#include "segmentation/segmentation_io.hpp"

#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "io/image_io.hpp"

namespace semap {

nlohmann::json segmentation_to_json(const SegmentationResult& result, const std::string& image_name, cv::Size size,
                                    const std::string& model) {
  nlohmann::json j;
  j["image"] = image_name;
  j["width"] = size.width;
  j["height"] = size.height;
  j["model"] = model;
  j["instances"] = nlohmann::json::array();
  for (const auto& inst : result.instances) {
    nlohmann::json ji;
    ji["id"] = inst.id;
    ji["class"] = std::string(class_name(inst.class_id));
    ji["class_id"] = inst.class_id;
    ji["score"] = inst.score;
    ji["box"] = {inst.box.x, inst.box.y, inst.box.width, inst.box.height};
    if (!inst.class_scores.empty()) {
      nlohmann::json scores = nlohmann::json::object();
      for (int c = 0; c < int(inst.class_scores.size()); ++c)
        if (inst.class_scores[c] >= 0.01f) scores[std::string(class_name(ClassId(c)))] = inst.class_scores[c];
      ji["class_scores"] = scores;
    }
    j["instances"].push_back(ji);
  }
  return j;
}

cv::Mat draw_overlay(const cv::Mat& bgr, const SegmentationResult& result) {
  cv::Mat out = bgr.clone();
  if (result.labels.empty() || result.labels.size() != bgr.size()) return out;
  cv::Mat colour(bgr.size(), CV_8UC3, cv::Scalar::all(0));
  for (int y = 0; y < bgr.rows; ++y) {
    const uint8_t* l = result.labels.ptr<uint8_t>(y);
    cv::Vec3b* c = colour.ptr<cv::Vec3b>(y);
    for (int x = 0; x < bgr.cols; ++x) {
      const Rgb8 p = class_colour(l[x]);
      c[x] = cv::Vec3b(p.b, p.g, p.r);
    }
  }
  cv::Mat blended;
  cv::addWeighted(bgr, 0.5, colour, 0.5, 0, blended);
  blended.copyTo(out, result.labels > 0);
  for (const auto& inst : result.instances) {
    const Rgb8 p = class_colour(inst.class_id);
    const cv::Scalar col(p.b, p.g, p.r);
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(inst.mask.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    cv::drawContours(out, contours, -1, col, 2);
    cv::rectangle(out, inst.box, col, 1);
    const std::string text = std::string(class_name(inst.class_id)) + " " + cv::format("%.2f", inst.score);
    cv::putText(out, text, inst.box.tl() + cv::Point(2, 14), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 3);
    cv::putText(out, text, inst.box.tl() + cv::Point(2, 14), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1);
  }
  return out;
}

void write_segmentation(const std::filesystem::path& dir, const std::string& name, const cv::Mat& bgr,
                        const SegmentationResult& result, const std::string& model) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(dir, "cannot create output folder: " + ec.message());
  cv::Mat label16, inst16;
  if (!result.labels.empty()) result.labels.convertTo(label16, CV_16U);
  else label16 = cv::Mat::zeros(bgr.size(), CV_16UC1);
  inst16 = result.instance_ids.empty() ? cv::Mat::zeros(label16.size(), CV_16UC1) : result.instance_ids;
  write_image(dir / (name + ".label.png"), label16);
  write_image(dir / (name + ".instances.png"), inst16);
  write_file_atomic(dir / (name + ".json"), segmentation_to_json(result, name, label16.size(), model).dump(2) + "\n");
  write_image(dir / (name + ".overlay.png"), draw_overlay(bgr, result));
}

}  // namespace semap
