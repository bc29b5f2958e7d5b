#pragma once
// Model class vocabularies -> the project label set (core/labels.hpp). The one place where
// model class ids are translated; unknown names map to "other", never an error.
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "semap/core/labels.hpp"

namespace semap {

struct SegmentationConfig;

/// Project class of a free-form class name ("dining table", "tvmonitor", "025_mug", "Chairs"):
/// lower-cased, '_'/'-' as spaces, leading digits dropped, aliases (COCO, VOC, NYU/ScanNet,
/// YCB) tried, then a plural 's' dropped. "background"/"void"/"unlabelled" -> unlabelled (0);
/// anything unknown -> other.
ClassId map_class_name(std::string_view name);

/// The built-in class lists (index = model class id), as in ../shared/models/coco80.txt,
/// voc21.txt and ade20k32.txt (index 0 "other" = any ADE20K class outside the 31 kept).
const std::vector<std::string>& coco80_class_names();
const std::vector<std::string>& voc21_class_names();
const std::vector<std::string>& ade20k32_class_names();

/// Reads one class name per line (blank trailing lines ignored). Throws semap::Error naming
/// the file when it is missing or empty.
std::vector<std::string> read_class_names(const std::filesystem::path& path);

class ClassMapping {
 public:
  ClassMapping() = default;
  /// `overrides` entries read "model_name=project_name" and win over map_class_name(); an
  /// unknown project name is a semap::Error naming the entry.
  explicit ClassMapping(std::vector<std::string> model_names, const std::vector<std::string>& overrides = {});

  /// Project class of a model class id; ids outside the list map to "other".
  ClassId map(int model_class) const {
    return model_class >= 0 && model_class < static_cast<int>(table_.size()) ? table_[model_class] : id(Label::kOther);
  }
  size_t size() const { return table_.size(); }
  const std::vector<std::string>& model_names() const { return names_; }
  const std::vector<ClassId>& table() const { return table_; }

 private:
  std::vector<std::string> names_;
  std::vector<ClassId> table_;
};

/// The mapping for a model with `model_class_count` classes: `network_class_names_file` (the
/// network's own segmentation.yolo/semantic.class_names_file) when set, else
/// config.class_names_file when set (its line count must match), else the built-in COCO-80
/// (80 classes), VOC-21 (21) or ADE20K-32 (32) list, else every class maps to "other" (a
/// warning is logged). config.class_map overrides apply.
ClassMapping make_class_mapping(const SegmentationConfig& config, int model_class_count, const std::string& model_path,
                                const std::string& network_class_names_file = {});

}  // namespace semap
