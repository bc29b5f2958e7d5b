// Helpers shared by the dataset layouts: TUM-style lists, ground-truth lookup, dataset.yaml.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <set>

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "io/association.hpp"
#include "semap/io/config_loader.hpp"
#include "io/dataset_layouts.hpp"
#include "io/text_util.hpp"

namespace semap::io_detail {

namespace fs = std::filesystem;

std::vector<ListEntry> read_list(const fs::path& path, size_t min_fields) {
  const std::string text = read_file_bytes(path, kMaxTextFileBytes, "list file");
  const std::string source = path.string();
  std::vector<ListEntry> entries;
  for_each_line(text, [&](std::string_view line, size_t line_no) {
    if (is_blank_or_comment(line)) return;
    const auto fields = split_fields(line);
    if (fields.size() < 1 + min_fields)
      throw Error(where(source, line_no), "expected 'timestamp' and " + std::to_string(min_fields) + " more field(s)");
    const auto t = parse_double(fields[0]);
    if (!t) throw Error(where(source, line_no), "malformed timestamp " + quoted_field(fields[0]));
    if (!std::isfinite(*t)) throw Error(where(source, line_no), "NaN or Inf timestamp");
    if (!entries.empty() && *t <= entries.back().timestamp)
      throw Error(where(source, line_no), *t == entries.back().timestamp ? "duplicate timestamp" : "timestamp not increasing");
    ListEntry e{*t, {}, line_no};
    for (size_t k = 1; k < fields.size(); ++k) e.fields.emplace_back(fields[k]);
    entries.push_back(std::move(e));
  });
  return entries;
}

namespace {

/// Lists name files relative to their folder. One outside it (absolute, or "../") is read as
/// given, with one warning per list (README "Reliability"): associate.py output with absolute
/// paths is common, and reading an image is harmless (regular files only, size-limited).
void warn_if_outside(const fs::path& list, const fs::path& relative, size_t line) {
  const fs::path normal = relative.lexically_normal();
  if (!normal.is_absolute() && (normal.empty() || *normal.begin() != "..")) return;
  static std::mutex mutex;
  static std::set<std::string> warned;
  const std::lock_guard<std::mutex> lock(mutex);
  if (!warned.insert(list.string()).second) return;
  spdlog::warn("{}: lists files outside the dataset folder (first: {}); they are read as given",
               where(list.string(), line), message_text(relative.string()));
}

/// A hint when the name was split at spaces: the joined name exists.
std::string space_hint(const fs::path& list, const ListEntry& entry, size_t field) {
  std::string joined = entry.fields[field];
  for (size_t k = field + 1; k < entry.fields.size(); ++k) {
    joined += " " + entry.fields[k];
    if (is_regular_file_path(list.parent_path() / joined))
      return " (list fields are split at spaces and tabs: '" + message_text(joined) +
             "' exists; rename it without spaces)";
  }
  return entry.fields.size() > field + 1 ? " (list fields are split at spaces and tabs: file names with spaces are not supported)" : "";
}

}  // namespace

fs::path listed_file(const fs::path& list, const ListEntry& entry, size_t field) {
  const fs::path relative = entry.fields.at(field);
  const fs::path file = list.parent_path() / relative;
  warn_if_outside(list, relative, entry.line);
  if (is_regular_file_path(file)) return file;
  const std::string is = describe_path(file);
  const std::string problem = is == "not found" ? "not found" : "is " + is + ", expected a regular file";
  throw Error(where(list.string(), entry.line),
              "listed image " + file.string() + " " + problem + (is == "not found" ? space_hint(list, entry, field) : ""));
}

std::optional<Pose> pose_at(const Trajectory& trajectory, double t, double max_dt) {
  const auto next = std::lower_bound(trajectory.begin(), trajectory.end(), t,
                                     [](const StampedPose& p, double s) { return p.timestamp < s; });
  const bool has_next = next != trajectory.end() && next->timestamp - t <= max_dt;
  const bool has_prev = next != trajectory.begin() && t - std::prev(next)->timestamp <= max_dt;
  if (has_next && next->timestamp == t) return next->T_world_camera;
  if (has_next && has_prev) {
    const StampedPose& a = *std::prev(next);
    const StampedPose& b = *next;
    return interpolate_pose(a.T_world_camera, b.T_world_camera, (t - a.timestamp) / (b.timestamp - a.timestamp));
  }
  if (has_next) return next->T_world_camera;
  if (has_prev) return std::prev(next)->T_world_camera;
  return std::nullopt;
}

Pose pose_from_rows(const std::vector<double>& m, const std::string& where) {
  if (m.size() != 12 && m.size() != 16) throw Error(where, "expected a 3x4 or 4x4 matrix");
  Pose pose = Pose::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = m[r * 4 + c];
  // Stored rotations have ~7 digits; larger errors mean the file is not a rigid transform.
  if (!is_valid_pose(pose, 1e-3)) throw Error(where, "matrix is not a rigid transform (rotation not orthonormal)");
  return orthonormalized(pose);
}

std::optional<Pose> read_matrix_pose(const fs::path& path) {
  const std::vector<double> m = read_numbers(path);
  if (m.size() == 16 || m.size() == 12)
    for (double v : m)
      if (!std::isfinite(v)) return std::nullopt;  // 7-Scenes marks unknown poses with inf
  return pose_from_rows(m, path.string());
}

std::vector<FrameRecord> associate_lists(const fs::path& rgb_list, const fs::path& depth_list) {
  const auto rgb = read_list(rgb_list), depth = read_list(depth_list);
  // Every listed image must exist, associated or not: a list naming absent files is broken.
  std::vector<double> rgb_t, depth_t;
  std::vector<fs::path> rgb_files, depth_files;
  for (const auto& e : rgb) rgb_t.push_back(e.timestamp), rgb_files.push_back(listed_file(rgb_list, e, 0));
  for (const auto& e : depth) depth_t.push_back(e.timestamp), depth_files.push_back(listed_file(depth_list, e, 0));
  std::vector<FrameRecord> records;
  for (const auto& [i, j] : associate_timestamps(rgb_t, depth_t, kMaxTimeDifference)) {
    FrameRecord r;
    r.timestamp = rgb[i].timestamp;
    r.rgb = rgb_files[i];
    r.depth = depth_files[j];
    records.push_back(std::move(r));
  }
  return records;
}

void attach_ground_truth(std::vector<FrameRecord>& records, const Trajectory& trajectory, const std::string& source) {
  for (auto& r : records) r.gt_T_world_camera = pose_at(trajectory, r.timestamp);
  use_local_origin_if_far(records, source);
}

void use_local_origin_if_far(std::vector<FrameRecord>& records, const std::string& source) {
  const Pose* first = nullptr;
  double farthest = 0.0;
  for (const auto& r : records) {
    if (!r.gt_T_world_camera) continue;
    if (!first) first = &*r.gt_T_world_camera;
    farthest = std::max(farthest, r.gt_T_world_camera->translation().norm());
  }
  if (!first || farthest <= kMaxGroundTruthDistanceM) return;
  const Eigen::Vector3d origin = first->translation();
  spdlog::warn("{}: ground-truth positions lie up to {} m from the origin (georeferenced?); using a local origin: "
               "the first pose's translation ({}, {}, {}) is subtracted from every ground-truth pose",
               message_text(source), compact_number(farthest), origin.x(), origin.y(), origin.z());
  for (auto& r : records)
    if (r.gt_T_world_camera) r.gt_T_world_camera->translation() -= origin;
}

// ------------------------------------------------------------------ dataset.yaml

namespace {

void read_top_level(const YAML::Node& root, const fs::path& file, DatasetYaml& yaml) {
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (key == "format") {
      if (!kv.second.IsScalar()) throw Error(file, "'format' must be a string");
      yaml.format = kv.second.as<std::string>();
    } else if (key == "camera") {
      if (!kv.second.IsMap()) throw Error(file, "'camera' must be a map");
      yaml.camera = kv.second;
    } else if (key != "name" && key != "description" && key != "generator") {
      throw Error(file, "unknown key '" + key + "'");
    }
  }
}

double yaml_number(const YAML::Node& node, const std::string& file, const std::string& key) {
  try {
    const double v = node.as<double>();
    if (std::isfinite(v)) return v;
  } catch (const YAML::Exception&) {
  }
  throw Error(file, "'" + key + "' must be a finite number");
}

int yaml_size(const YAML::Node& node, const std::string& file, const std::string& key) {
  const double v = yaml_number(node, file, key);
  if (v < 1 || v > 16384 || v != std::floor(v)) throw Error(file, "'" + key + "' must be an integer in 1..16384");
  return static_cast<int>(v);
}

void apply_intrinsics(const YAML::Node& map, const std::string& file, const std::string& prefix,
                      PinholeIntrinsics& k, double* depth_scale, Pose* T_depth_colour, bool* has_colour,
                      std::array<double, 5>* distortion) {
  for (const auto& kv : map) {
    const std::string key = kv.first.as<std::string>();
    const std::string full = prefix + key;
    if (key == "fx") k.fx = yaml_number(kv.second, file, full);
    else if (key == "fy") k.fy = yaml_number(kv.second, file, full);
    else if (key == "cx") k.cx = yaml_number(kv.second, file, full);
    else if (key == "cy") k.cy = yaml_number(kv.second, file, full);
    else if (key == "width") k.width = yaml_size(kv.second, file, full);
    else if (key == "height") k.height = yaml_size(kv.second, file, full);
    else if (key == "depth_scale" && depth_scale) *depth_scale = yaml_number(kv.second, file, full);
    else if (key == "distortion" && distortion) {
      if (!kv.second.IsSequence() || kv.second.size() != 5)
        throw Error(file, "'" + full + "' must list 5 numbers (OpenCV order k1 k2 p1 p2 k3)");
      for (size_t j = 0; j < 5; ++j) (*distortion)[j] = yaml_number(kv.second[j], file, full);
    }
    else if (key == "T_depth_colour" && T_depth_colour) {
      if (!kv.second.IsSequence() || kv.second.size() != 16) throw Error(file, "'" + full + "' must list 16 numbers");
      std::vector<double> m;
      for (const auto& v : kv.second) m.push_back(yaml_number(v, file, full));
      *T_depth_colour = pose_from_rows(m, file + ": " + full);
    } else if (key == "colour" && has_colour) {
      if (!kv.second.IsMap()) throw Error(file, "'" + full + "' must be a map");
      *has_colour = true;
    } else {
      throw Error(file, "unknown key '" + full + "'");
    }
  }
  if (!(k.fx > 0 && k.fy > 0)) throw Error(file, "'" + prefix + "fx/fy' must be positive");
}

void apply_camera_node(const YAML::Node& node, const std::string& file, CameraModel& camera) {
  bool has_colour = false;
  apply_intrinsics(node, file, "camera.", camera.depth, &camera.depth_scale, nullptr, &has_colour, &camera.distortion);
  if (!(camera.depth_scale > 0)) throw Error(file, "'camera.depth_scale' must be positive");
  if (has_colour) {
    CameraModel::ColourCamera colour;
    colour.intrinsics = camera.depth;  // unspecified keys default to the depth camera's
    apply_intrinsics(node["colour"], file, "camera.colour.", colour.intrinsics, nullptr, &colour.T_depth_colour,
                     nullptr, nullptr);
    camera.colour = colour;
  }
}

}  // namespace

DatasetYaml read_dataset_yaml(const fs::path& file) {
  DatasetYaml yaml;
  yaml.file = file;
  try {
    const YAML::Node root = parse_yaml_strict(read_file_bytes(file, kMaxTextFileBytes, "dataset.yaml"), file.string());
    if (!root.IsMap()) throw Error(file, "expected a map with 'format' and 'camera'");
    read_top_level(root, file, yaml);
  } catch (const YAML::Exception& e) {
    throw Error(file, std::string("malformed YAML: ") + e.what());
  }
  return yaml;
}

void apply_yaml_camera(const DatasetYaml* yaml, CameraModel& camera) {
  if (!yaml || !yaml->camera) return;
  try {
    apply_camera_node(yaml->camera, yaml->file.string(), camera);
  } catch (const YAML::Exception& e) {
    throw Error(yaml->file, std::string("malformed camera section: ") + e.what());
  }
  validate_camera(camera, yaml->file.string());
}

}  // namespace semap::io_detail
