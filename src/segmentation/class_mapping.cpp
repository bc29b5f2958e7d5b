#include "segmentation/class_mapping.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <sstream>
#include <unordered_map>

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "semap/segmentation/segmentation_config.hpp"

namespace semap {
namespace {

std::string normalise(std::string_view name) {
  std::string s;
  for (char c : name) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (c == '_' || c == '-' || c == '/' || std::isspace(u)) s += ' ';
    else s += static_cast<char>(std::tolower(u));
  }
  // Drop leading dataset numbering ("025 mug", "3 chair").
  size_t start = 0;
  while (start < s.size() && (std::isdigit(static_cast<unsigned char>(s[start])) || s[start] == ' ')) ++start;
  s = s.substr(start);
  while (!s.empty() && s.back() == ' ') s.pop_back();
  // Collapse repeated spaces.
  std::string out;
  for (char c : s)
    if (!(c == ' ' && !out.empty() && out.back() == ' ')) out += c;
  return out;
}

// Aliases of model class names (COCO-80, VOC-21, ADE20K, NYU/ScanNet, YCB) -> project class names.
const std::unordered_map<std::string, std::string>& aliases() {
  static const std::unordered_map<std::string, std::string> table = {
      {"background", "unlabelled"}, {"void", "unlabelled"}, {"unlabeled", "unlabelled"}, {"none", "unlabelled"},
      {"tv", "monitor"}, {"tvmonitor", "monitor"}, {"tv monitor", "monitor"}, {"television", "monitor"},
      {"computer monitor", "monitor"}, {"screen", "monitor"}, {"display", "monitor"},
      {"dining table", "table"}, {"diningtable", "table"}, {"coffee table", "table"}, {"kitchen table", "table"},
      {"couch", "sofa"}, {"potted plant", "plant"}, {"pottedplant", "plant"}, {"houseplant", "plant"},
      {"flower", "plant"}, {"cell phone", "phone"}, {"cellphone", "phone"}, {"mobile phone", "phone"},
      {"telephone", "phone"}, {"backpack", "bag"}, {"handbag", "bag"}, {"suitcase", "bag"},
      {"wine glass", "cup"}, {"mug", "cup"}, {"glass", "cup"}, {"teddy bear", "teddy"}, {"stuffed animal", "teddy"},
      {"bookshelf", "bookcase"}, {"bookshelves", "bookcase"}, {"shelves", "shelf"}, {"fridge", "refrigerator"},
      {"remote control", "remote"}, {"computer keyboard", "keyboard"}, {"computer mouse", "mouse"},
      {"notebook", "laptop"}, {"armchair", "chair"}, {"office chair", "chair"}, {"stool", "chair"},
      {"bench", "other"}, {"carpet", "rug"}, {"carpeting", "rug"}, {"floor mat", "rug"},
      {"blinds", "window"}, {"drape", "curtain"}, {"drapes", "curtain"}, {"cupboard", "cabinet"}, {"dresser", "cabinet"},
      {"nightstand", "cabinet"}, {"night stand", "cabinet"}, {"kitchen cabinet", "cabinet"},
      {"microwave oven", "microwave"}, {"stove", "oven"}, {"cardboard box", "box"}, {"gelatin box", "box"},
      {"cracker box", "box"}, {"sugar box", "box"}, {"pudding box", "box"}, {"bathtub", "other"},
      {"desk lamp", "lamp"}, {"light", "lamp"}, {"pitcher base", "other"}, {"people", "person"},
      {"man", "person"}, {"woman", "person"}, {"sofa chair", "sofa"},
      // ADE20K (issue 38). armchair stays "chair" (above): ScanNet/NYU40 file armchairs under
      // chair, and the COCO instance model calls them chair (or couch) too, so both networks agree.
      {"windowpane", "window"}, {"painting", "picture"}, {"poster", "picture"}, {"photo", "picture"},
      {"picture frame", "picture"}, {"mirror stuff", "mirror"},
  };
  return table;
}

std::optional<ClassId> lookup(const std::string& n) {
  if (n.empty()) return std::nullopt;
  if (auto it = aliases().find(n); it != aliases().end()) return class_from_name(it->second);
  if (auto c = class_from_name(n)) return c;
  return std::nullopt;
}

}  // namespace

ClassId map_class_name(std::string_view name) {
  const std::string n = normalise(name);
  if (auto c = lookup(n)) return *c;
  if (n.size() > 1 && n.back() == 's')
    if (auto c = lookup(n.substr(0, n.size() - 1))) return *c;
  // Last word ("red mug", "master chef can" -> "can" unknown -> other).
  if (const size_t space = n.rfind(' '); space != std::string::npos)
    if (auto c = lookup(n.substr(space + 1))) return *c;
  return id(Label::kOther);
}

const std::vector<std::string>& coco80_class_names() {
  static const std::vector<std::string> names = {
      "person", "bicycle", "car", "motorcycle", "airplane", "bus", "train", "truck", "boat", "traffic light",
      "fire hydrant", "stop sign", "parking meter", "bench", "bird", "cat", "dog", "horse", "sheep", "cow",
      "elephant", "bear", "zebra", "giraffe", "backpack", "umbrella", "handbag", "tie", "suitcase", "frisbee",
      "skis", "snowboard", "sports ball", "kite", "baseball bat", "baseball glove", "skateboard", "surfboard",
      "tennis racket", "bottle", "wine glass", "cup", "fork", "knife", "spoon", "bowl", "banana", "apple",
      "sandwich", "orange", "broccoli", "carrot", "hot dog", "pizza", "donut", "cake", "chair", "couch",
      "potted plant", "bed", "dining table", "toilet", "tv", "laptop", "mouse", "remote", "keyboard",
      "cell phone", "microwave", "oven", "toaster", "sink", "refrigerator", "book", "clock", "vase",
      "scissors", "teddy bear", "hair drier", "toothbrush"};
  return names;
}

const std::vector<std::string>& ade20k32_class_names() {
  static const std::vector<std::string> names = {
      "other", "wall", "building", "sky", "floor", "tree", "ceiling", "road", "bed", "windowpane", "grass",
      "cabinet", "sidewalk", "person", "earth", "door", "table", "mountain", "plant", "curtain", "chair", "car",
      "water", "painting", "sofa", "shelf", "house", "sea", "mirror", "rug", "field", "armchair"};
  return names;
}

const std::vector<std::string>& voc21_class_names() {
  static const std::vector<std::string> names = {
      "background", "aeroplane", "bicycle", "bird", "boat", "bottle", "bus", "car", "cat", "chair", "cow",
      "diningtable", "dog", "horse", "motorbike", "person", "pottedplant", "sheep", "sofa", "train", "tvmonitor"};
  return names;
}

std::vector<std::string> read_class_names(const std::filesystem::path& path) {
  std::istringstream in(read_regular_file(path, kMaxTextFileBytes, "class names file"));
  std::vector<std::string> names;
  std::string line;
  while (std::getline(in, line)) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    names.push_back(line);
  }
  while (!names.empty() && names.back().empty()) names.pop_back();
  if (names.empty()) throw Error(path, "class names file is empty");
  return names;
}

ClassMapping::ClassMapping(std::vector<std::string> model_names, const std::vector<std::string>& overrides)
    : names_(std::move(model_names)) {
  table_.reserve(names_.size());
  for (const auto& n : names_) table_.push_back(map_class_name(n));
  for (const auto& entry : overrides) {
    if (entry.empty()) continue;
    const size_t eq = entry.find('=');
    if (eq == std::string::npos) throw Error("segmentation.class_map", "entry '" + entry + "' must read model_name=project_name");
    const std::string model = entry.substr(0, eq);
    const auto project = class_from_name(entry.substr(eq + 1));
    if (!project) throw Error("segmentation.class_map", "unknown project class '" + entry.substr(eq + 1) + "'");
    for (size_t i = 0; i < names_.size(); ++i)
      if (names_[i] == model) table_[i] = *project;
  }
}

ClassMapping make_class_mapping(const SegmentationConfig& config, int model_class_count, const std::string& model_path,
                                const std::string& network_class_names_file) {
  const std::string& file = network_class_names_file.empty() ? config.class_names_file : network_class_names_file;
  std::vector<std::string> names;
  if (!file.empty()) {
    names = read_class_names(file);
    if (static_cast<int>(names.size()) != model_class_count)
      throw Error(file, "lists " + std::to_string(names.size()) + " classes but the model " + model_path + " has " +
                            std::to_string(model_class_count));
  } else if (model_class_count == 80) {
    names = coco80_class_names();
  } else if (model_class_count == 21) {
    names = voc21_class_names();
  } else if (model_class_count == 32) {
    names = ade20k32_class_names();
  } else {
    spdlog::warn("{}: {} classes and no segmentation.class_names_file: every class maps to 'other'", model_path,
                 model_class_count);
    names.assign(model_class_count, "other");
  }
  return ClassMapping(std::move(names), config.class_map);
}

}  // namespace semap
