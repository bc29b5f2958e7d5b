#include "semap/eval/object_metrics.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <string>

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "eval/nearest_neighbors.hpp"
#include "io/json_number.hpp"
#include "semap/io/ply_io.hpp"
#include "core/json_text.hpp"

namespace semap {
namespace {

using VoxelSet = std::vector<uint64_t>;  // sorted, unique packed voxel keys

/// Points each side of an object evaluation may hold together (12 bytes each; 10M map points
/// measured 0.57 GB peak with their k-d trees): the surface samples of all ground-truth boxes of
/// a scene.json, and the points of all map objects of an objects.json. A file of thousands of large boxes, or of thousands of
/// objects naming one large points file, is refused, not read into gigabytes (issue 44, class 2;
/// README, reliability).
constexpr size_t kMaxObjectEvalPoints = 20'000'000;

// Origin of the evaluation grid, in voxels. Not 0 (nor any simple fraction): synthetic and built
// scenes put faces at round coordinates, and a face on a cell border splits between two voxel
// layers by float rounding, so a perfect map of it scored IoU ~0.5 (test
// PerfectMapOfGridAlignedFacesScoresOne). Any origin is an equally valid grid for real data.
constexpr double kGridPhase[3] = {0.2871, 0.3713, 0.4127};

VoxelSet voxelize(const std::vector<Eigen::Vector3f>& points, double voxel_size) {
  VoxelSet keys;
  keys.reserve(points.size());
  constexpr int64_t kOffset = 1 << 20;  // 21 bits per axis: +-2^20 voxels
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const int64_t v = static_cast<int64_t>(std::floor(p[a] / voxel_size + kGridPhase[a])) + kOffset;
      key = (key << 21) | static_cast<uint64_t>(std::clamp<int64_t>(v, 0, (1 << 21) - 1));
    }
    keys.push_back(key);
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

size_t intersection_size(const VoxelSet& a, const VoxelSet& b) {
  size_t n = 0;
  auto i = a.begin(), j = b.begin();
  while (i != a.end() && j != b.end()) {
    if (*i < *j) ++i;
    else if (*j < *i) ++j;
    else { ++n; ++i; ++j; }
  }
  return n;
}

double iou(const VoxelSet& a, const VoxelSet& b) {
  if (a.empty() || b.empty()) return 0.0;
  if (a.back() < b.front() || b.back() < a.front()) return 0.0;
  const size_t inter = intersection_size(a, b);
  return static_cast<double>(inter) / static_cast<double>(a.size() + b.size() - inter);
}

struct Bounds {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
  Eigen::Vector3f hi = -lo;
};

Bounds bounds_of(const std::vector<Eigen::Vector3f>& points) {
  Bounds b;
  for (const auto& p : points)
    if (p.allFinite()) {
      b.lo = b.lo.cwiseMin(p);
      b.hi = b.hi.cwiseMax(p);
    }
  return b;
}

bool within(const Bounds& a, const Bounds& b, float distance) {
  return ((a.lo.array() - distance) <= b.hi.array()).all() && ((b.lo.array() - distance) <= a.hi.array()).all();
}

/// Fraction of `points` within `distance` of the set `index` was built on.
double fraction_within(const eval_detail::NearestNeighborIndex& index, const std::vector<Eigen::Vector3f>& points,
                       float distance) {
  if (points.empty()) return 0.0;
  size_t near = 0;
  for (const auto& hit : index.nearest_all(points)) near += hit.distance <= distance ? 1 : 0;
  return static_cast<double>(near) / static_cast<double>(points.size());
}

struct SurfaceOverlap {
  double precision = 0.0, recall = 0.0;
  double iou() const {
    if (precision <= 0.0 || recall <= 0.0) return 0.0;
    return precision * recall / (precision + recall - precision * recall);
  }
};

std::vector<Eigen::Vector3f> finite_points(const std::vector<Eigen::Vector3f>& points) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(points.size());
  for (const auto& p : points)
    if (p.allFinite()) out.push_back(p);
  return out;
}

/// One side's objects ready for distance queries (finite points, k-d tree, box).
struct IndexedObjects {
  std::vector<std::vector<Eigen::Vector3f>> points;
  std::vector<std::unique_ptr<eval_detail::NearestNeighborIndex>> index;
  std::vector<Bounds> bounds;
  explicit IndexedObjects(const std::vector<EvalObject>& objects) {
    points.reserve(objects.size());  // the indices keep references into `points`
    for (const auto& o : objects) {
      points.push_back(finite_points(o.points));
      index.push_back(std::make_unique<eval_detail::NearestNeighborIndex>(points.back()));
      bounds.push_back(bounds_of(points.back()));
    }
  }
};

/// A (GT, map) pair whose surfaces overlap (recall > 0).
struct PairOverlap {
  size_t gt = 0, map = 0;
  SurfaceOverlap overlap;
};

/// Precision and recall at distance d (header) of the (GT, map) pairs that overlap, sorted by GT
/// then map index; pairs whose boxes are farther apart than d are disjoint and not searched.
/// Sparse: a dense GT x map table of a few thousand objects each took gigabytes (issue 44,
/// class 2). Non-finite map points count against precision.
std::vector<PairOverlap> surface_overlaps(const std::vector<EvalObject>& gt, const std::vector<EvalObject>& map,
                                          float distance) {
  const IndexedObjects g(gt), m(map);
  std::vector<PairOverlap> overlaps;
  for (size_t i = 0; i < gt.size(); ++i)
    for (size_t j = 0; j < map.size(); ++j) {
      if (!within(g.bounds[i], m.bounds[j], distance)) continue;
      SurfaceOverlap o;
      o.recall = fraction_within(*m.index[j], g.points[i], distance);
      if (o.recall <= 0.0) continue;
      if (!map[j].points.empty())
        o.precision = fraction_within(*g.index[i], m.points[j], distance) *
                      static_cast<double>(m.points[j].size()) / static_cast<double>(map[j].points.size());
      overlaps.push_back({i, j, o});
    }
  return overlaps;
}

std::vector<ObjectClassCount> count_per_class(const std::vector<EvalObject>& gt, const std::vector<EvalObject>& map) {
  std::map<ClassId, ObjectClassCount> counts;
  for (const auto& g : gt) ++counts[g.class_id].gt;
  for (const auto& m : map) ++counts[m.class_id].map;
  std::vector<ObjectClassCount> out;
  for (auto& [c, count] : counts) {
    count.class_id = c;
    out.push_back(count);
  }
  return out;
}

/// Greedy one-to-one same-class matching by descending IoU, per threshold (header).
std::vector<ObjectMatchStats> match_instances(const std::vector<EvalObject>& gt, const std::vector<EvalObject>& map,
                                              const std::vector<PairOverlap>& overlaps,
                                              const std::vector<double>& thresholds) {
  struct Candidate { double iou; size_t i, j; };
  std::vector<Candidate> candidates;
  for (const PairOverlap& p : overlaps)
    if (const double v = p.overlap.iou(); gt[p.gt].class_id == map[p.map].class_id && v > 0.0)
      candidates.push_back({v, p.gt, p.map});
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.iou > b.iou; });
  std::vector<ObjectMatchStats> out;
  for (double threshold : thresholds) {
    ObjectMatchStats stats;
    stats.iou_threshold = threshold;
    std::vector<bool> gt_used(gt.size(), false), map_used(map.size(), false);
    for (const auto& c : candidates) {
      if (c.iou < threshold) break;
      if (gt_used[c.i] || map_used[c.j]) continue;
      gt_used[c.i] = map_used[c.j] = true;
      ++stats.true_positives;
    }
    const double tp = static_cast<double>(stats.true_positives);
    stats.precision = map.empty() ? 0.0 : tp / static_cast<double>(map.size());
    stats.recall = gt.empty() ? 0.0 : tp / static_cast<double>(gt.size());
    out.push_back(stats);
  }
  return out;
}

nlohmann::json read_json(const std::filesystem::path& path) {
  const std::string text = read_regular_file(path, kMaxTextFileBytes, "JSON file");
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw Error(path, "malformed JSON: " + json_error_text(e));
  }
}

/// Objects are matched and counted by id: a repeated id would count one object twice.
void require_unique_ids(const std::vector<EvalObject>& objects, const std::filesystem::path& file, const char* key) {
  std::map<uint32_t, size_t> first;
  for (size_t k = 0; k < objects.size(); ++k)
    if (const auto [it, added] = first.emplace(objects[k].id, k); !added)
      throw Error(file, std::string("\"") + key + "\" " + std::to_string(objects[k].id) + " appears twice (objects " +
                            std::to_string(it->second) + " and " + std::to_string(k) + "): ids must be unique");
}

ClassId class_of(const nlohmann::json& object) {
  if (object.contains("class_id") && object["class_id"].is_number_integer()) {
    const int c = static_cast<int>(json_number(object["class_id"], "class_id", -1e9, 1e9, true));
    if (c >= 0 && c < kNumClasses) return static_cast<ClassId>(c);
  }
  if (object.contains("class") && object["class"].is_string())
    if (auto c = class_from_name(object["class"].get<std::string>())) return *c;
  return id(Label::kOther);
}

Eigen::Vector3d vec3(const nlohmann::json& j, const char* key) {
  const auto& a = j.at(key);
  if (!a.is_array() || a.size() != 3) throw std::invalid_argument(std::string(key) + " needs 3 numbers");
  return {a[0].get<double>(), a[1].get<double>(), a[2].get<double>()};
}

// Samples the six faces of an oriented box (rotation row-major world_from_box, full extents).
void sample_box_surface(const nlohmann::json& obb, double spacing, std::vector<Eigen::Vector3f>& out) {
  const Eigen::Vector3d center = vec3(obb, "center");
  const Eigen::Vector3d half = 0.5 * vec3(obb, "extent");
  const auto& r = obb.at("rotation");
  if (!r.is_array() || r.size() != 9) throw std::invalid_argument("rotation needs 9 numbers");
  Eigen::Matrix3d R;
  for (int k = 0; k < 9; ++k) R(k / 3, k % 3) = r[k].get<double>();
  if (!half.allFinite() || (half.array() < 0).any() || !R.allFinite())
    throw std::invalid_argument("invalid box");
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    // A huge box (or a tiny spacing) must not make us sample billions of points.
    constexpr double kMaxSamplesPerFace = 1e7;
    const double su = std::ceil(2 * half[u] / spacing), sv = std::ceil(2 * half[v] / spacing);
    if (!(su * sv <= kMaxSamplesPerFace))
      throw std::invalid_argument("box face of " + compact_number(2 * half[u]) + " x " + compact_number(2 * half[v]) +
                                  " m is too large to sample every " + compact_number(spacing) + " m");
    const int nu = std::max(1, static_cast<int>(su));
    const int nv = std::max(1, static_cast<int>(sv));
    for (double side : {-1.0, 1.0})
      for (int iu = 0; iu <= nu; ++iu)
        for (int iv = 0; iv <= nv; ++iv) {
          Eigen::Vector3d local;
          local[axis] = side * half[axis];
          local[u] = -half[u] + 2 * half[u] * iu / nu;
          local[v] = -half[v] + 2 * half[v] * iv / nv;
          out.push_back((center + R * local).cast<float>());
        }
  }
}

}  // namespace

ObjectEvaluation evaluate_objects(const std::vector<EvalObject>& gt, const std::vector<EvalObject>& map,
                                  const ObjectEvalOptions& options) {
  if (!(options.voxel_size_m > 0.0)) throw Error("object eval", "voxel size must be > 0");
  if (!(options.match_distance_m > 0.0)) throw Error("object eval", "match distance must be > 0");
  ObjectEvaluation result;
  result.gt_objects = gt.size();
  result.map_objects = map.size();
  result.counts = count_per_class(gt, map);

  std::vector<VoxelSet> gt_voxels, map_voxels;
  for (const auto& g : gt) gt_voxels.push_back(voxelize(g.points, options.voxel_size_m));
  for (const auto& m : map) map_voxels.push_back(voxelize(m.points, options.voxel_size_m));
  const auto overlaps = surface_overlaps(gt, map, static_cast<float>(options.match_distance_m));

  // METHODS.md C6: WOv weighted by GT surface area (occupied voxels).
  double weight_sum = 0.0, wov_sum = 0.0, wov_same_sum = 0.0, wov_voxel_sum = 0.0;
  auto pair = overlaps.begin();  // sorted by GT index
  for (size_t i = 0; i < gt.size(); ++i) {
    GtObjectScore score{.gt_id = gt[i].id, .class_id = gt[i].class_id, .voxels = gt_voxels[i].size()};
    for (; pair != overlaps.end() && pair->gt == i; ++pair) {
      const size_t j = pair->map;
      const double v = pair->overlap.iou();
      if (v > score.best_iou) {
        score.best_iou = v;
        score.best_map_id = map[j].id;
        score.best_precision = pair->overlap.precision;
        score.best_recall = pair->overlap.recall;
      }
      if (map[j].class_id == gt[i].class_id) score.best_iou_same_class = std::max(score.best_iou_same_class, v);
    }
    double best_voxel_iou = 0.0;
    for (size_t j = 0; j < map.size(); ++j) best_voxel_iou = std::max(best_voxel_iou, iou(gt_voxels[i], map_voxels[j]));
    const double w = static_cast<double>(score.voxels);
    weight_sum += w;
    wov_sum += w * score.best_iou;
    wov_same_sum += w * score.best_iou_same_class;
    wov_voxel_sum += w * best_voxel_iou;
    result.per_gt.push_back(score);
  }
  if (weight_sum > 0) {
    result.wov = wov_sum / weight_sum;
    result.wov_same_class = wov_same_sum / weight_sum;
    result.wov_voxel = wov_voxel_sum / weight_sum;
  }
  result.matches = match_instances(gt, map, overlaps, options.iou_thresholds);
  return result;
}

std::vector<EvalObject> gt_objects_from_points(const PointCloud& cloud) {
  if (!cloud.has_instances() || cloud.instances.size() != cloud.size())
    throw Error("ground truth", "points carry no 'instance' property");
  if (!cloud.has_labels() || cloud.labels.size() != cloud.size())
    throw Error("ground truth", "points carry no 'label' property");
  std::map<uint32_t, EvalObject> objects;
  std::map<uint32_t, std::vector<size_t>> votes;
  for (size_t k = 0; k < cloud.size(); ++k) {
    const uint32_t inst = cloud.instances[k];
    if (inst == 0) continue;  // stuff
    auto& o = objects[inst];
    o.id = inst;
    o.points.push_back(cloud.points[k]);
    auto& v = votes[inst];
    if (v.empty()) v.assign(kNumClasses, 0);
    if (cloud.labels[k] < kNumClasses) ++v[cloud.labels[k]];
  }
  std::vector<EvalObject> out;
  for (auto& [inst, o] : objects) {
    const auto& v = votes[inst];
    // Majority of the non-zero labels.
    o.class_id = static_cast<ClassId>(std::max_element(v.begin() + 1, v.end()) - v.begin());
    if (v[o.class_id] == 0) o.class_id = 0;
    out.push_back(std::move(o));
  }
  return out;
}

std::vector<EvalObject> gt_objects_from_scene_json(const std::filesystem::path& path, double spacing) {
  const nlohmann::json scene = read_json(path);
  if (!scene.contains("objects") || !scene["objects"].is_array()) throw Error(path, "no \"objects\" array");
  std::vector<EvalObject> out;
  size_t k = 0, total_points = 0;
  for (const auto& jo : scene["objects"]) {
    try {
      EvalObject o;
      o.id = static_cast<uint32_t>(json_number(jo.at("instance_id"), "instance_id", 0, 4294967295.0, true));
      o.class_id = class_of(jo);
      if (jo.contains("primitives") && jo["primitives"].is_array() && !jo["primitives"].empty()) {
        for (const auto& prim : jo["primitives"]) sample_box_surface(prim, spacing, o.points);
      } else {
        sample_box_surface(jo.at("obb"), spacing, o.points);
      }
      total_points += o.points.size();
      out.push_back(std::move(o));
    } catch (const std::exception& e) {
      throw Error(path, "object " + std::to_string(k) + ": " + json_error_text(e));
    }
    if (total_points > kMaxObjectEvalPoints)
      throw Error(path, "the objects up to object " + std::to_string(k) + " sample to more than " +
                            std::to_string(kMaxObjectEvalPoints) + " surface points at " + compact_number(spacing) +
                            " m spacing (limit); evaluate fewer or smaller objects, or a larger --voxel");
    ++k;
  }
  require_unique_ids(out, path, "instance_id");
  return out;
}

std::vector<EvalObject> load_gt_objects(const std::filesystem::path& path, double spacing) {
  require_regular_file(path, "ground truth");
  const std::string ext = path.extension().string();
  if (ext == ".json") return gt_objects_from_scene_json(path, spacing);
  if (ext == ".ply") {
    const TriangleMesh mesh = read_ply(path);
    try {
      return gt_objects_from_points(mesh.vertices);
    } catch (const Error& e) {
      throw Error(path, e.reason());
    }
  }
  throw Error(path, "ground truth must be scene.json or gt_points.ply");
}

std::vector<EvalObject> load_map_objects(const std::filesystem::path& objects_json) {
  const nlohmann::json doc = read_json(objects_json);
  if (!doc.contains("objects") || !doc["objects"].is_array()) throw Error(objects_json, "no \"objects\" array");
  const auto folder = objects_json.parent_path();
  std::vector<EvalObject> out;
  std::map<std::filesystem::path, std::vector<Eigen::Vector3f>> read_files;  // a file named twice is read once
  size_t k = 0, total_points = 0;
  for (const auto& jo : doc["objects"]) {
    EvalObject o;
    try {
      o.id = static_cast<uint32_t>(json_number(jo.at("id"), "id", 0, 4294967295.0, true));
    } catch (const std::exception& e) {
      throw Error(objects_json, "object " + std::to_string(k) + ": missing/invalid \"id\"");
    }
    o.class_id = class_of(jo);
    const size_t point_count = jo.contains("point_count") && jo["point_count"].is_number_unsigned()
                                   ? static_cast<size_t>(json_number(jo["point_count"], "point_count", 0, 1e15, true)) : 1;
    if (jo.contains("points_file") && jo["points_file"].is_string()) {
      const auto file = folder / jo["points_file"].get<std::string>();
      if (std::filesystem::exists(file) || point_count > 0) {
        auto [it, inserted] = read_files.try_emplace(file);
        if (inserted) it->second = read_ply(file).vertices.points;
        total_points += it->second.size();
        if (total_points > kMaxObjectEvalPoints)
          throw Error(objects_json, "the objects up to object " + std::to_string(o.id) + " hold more than " +
                                        std::to_string(kMaxObjectEvalPoints) + " points (limit)");
        o.points = it->second;
      }
    } else if (point_count > 0) {
      throw Error(objects_json, "object " + std::to_string(o.id) + " has no \"points_file\"");
    }
    out.push_back(std::move(o));
    ++k;
  }
  require_unique_ids(out, objects_json, "id");
  return out;
}

ObjectEvaluation evaluate_object_files(const std::filesystem::path& gt_path,
                                       const std::filesystem::path& objects_json,
                                       const ObjectEvalOptions& options) {
  const auto gt = load_gt_objects(gt_path, 0.5 * options.voxel_size_m);
  const auto map = load_map_objects(objects_json);
  return evaluate_objects(gt, map, options);
}

nlohmann::json to_json(const ObjectEvaluation& e) {
  nlohmann::json counts = nlohmann::json::array();
  for (const auto& c : e.counts)
    counts.push_back({{"class", std::string(class_name(c.class_id))}, {"class_id", c.class_id},
                      {"gt", c.gt}, {"map", c.map}});
  nlohmann::json matches = nlohmann::json::array();
  for (const auto& m : e.matches)
    matches.push_back({{"iou_threshold", m.iou_threshold}, {"true_positives", m.true_positives},
                       {"precision", m.precision}, {"recall", m.recall}});
  nlohmann::json per_gt = nlohmann::json::array();
  for (const auto& g : e.per_gt)
    per_gt.push_back({{"gt_id", g.gt_id}, {"class", std::string(class_name(g.class_id))},
                      {"voxels", g.voxels}, {"best_iou", g.best_iou}, {"best_map_id", g.best_map_id},
                      {"best_precision", g.best_precision}, {"best_recall", g.best_recall},
                      {"best_iou_same_class", g.best_iou_same_class}});
  return {{"gt_objects", e.gt_objects}, {"map_objects", e.map_objects}, {"wov", e.wov},
          {"wov_same_class", e.wov_same_class}, {"wov_voxel", e.wov_voxel}, {"counts", counts}, {"matches", matches},
          {"per_gt", per_gt}};
}

}  // namespace semap
