#pragma once
// Files of one segmented image (what `semap segment` writes and PrecomputedSegmenter reads):
//   NAME.label.png      16-bit, project class ids (core/labels.hpp), 0 = unlabelled
//   NAME.instances.png  16-bit, instance ids, 0 = none
//   NAME.json           {"image": "rgb.png", "width": W, "height": H, "model": "yolo:...",
//                        "instances": [{"id": 1, "class": "cup", "class_id": 20, "score": 0.91,
//                                       "box": [x, y, w, h], "class_scores": {"cup": 0.91, ...}}]}
//   NAME.overlay.png    the image with masks, boxes and names drawn (for people)
// For external tools: "class" may be any name (mapped by map_class_name, unknown -> other);
// without "class", "class_id" is a project id. "class_scores" is optional (names -> scores).
// An optional top-level "label_names": ["bg", "chair", ...] says the label PNG holds that
// tool's own ids (index = value), mapped to project classes by name.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "semap/segmentation/segmenter.hpp"

namespace semap {

nlohmann::json segmentation_to_json(const SegmentationResult& result, const std::string& image_name,
                                    cv::Size size, const std::string& model);
/// The image with instance masks (or the label image) blended in the class palette, boxes and names.
cv::Mat draw_overlay(const cv::Mat& bgr, const SegmentationResult& result);
/// Writes the four files DIR/NAME.{label.png, instances.png, json, overlay.png}.
void write_segmentation(const std::filesystem::path& dir, const std::string& name, const cv::Mat& bgr,
                        const SegmentationResult& result, const std::string& model);

}  // namespace semap
