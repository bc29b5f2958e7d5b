#include "objects/object_map.hpp"

#include <algorithm>
#include <cmath>
#include <nanoflann.hpp>
#include <numeric>

#include "objects/segment_graph.hpp"

namespace semap {

const char* state_name(InstanceState state) {
  switch (state) {
    case InstanceState::kNew: return "new";
    case InstanceState::kUnstable: return "unstable";
    case InstanceState::kStable: return "stable";
  }
  return "unknown";
}

// A k-d tree over its own copy of the points (instances move when the map vector grows).
struct PointKdTree {
  struct Adaptor {
    const std::vector<Eigen::Vector3f>* points = nullptr;
    size_t kdtree_get_point_count() const { return points->size(); }
    float kdtree_get_pt(size_t i, size_t dim) const { return (*points)[i][static_cast<int>(dim)]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const { return false; }
  };
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Adaptor>, Adaptor, 3>;

  explicit PointKdTree(std::vector<Eigen::Vector3f> pts) : points(std::move(pts)) {
    adaptor.points = &points;
    index = std::make_unique<Index>(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    index->buildIndex();
  }
  /// Squared distance to the nearest point (infinity when empty).
  float nearest_sq(const Eigen::Vector3f& q, size_t* which = nullptr) const {
    if (points.empty()) return std::numeric_limits<float>::infinity();
    uint32_t idx = 0;
    float dist_sq = 0.f;
    index->knnSearch(q.data(), 1, &idx, &dist_sq);
    if (which) *which = idx;
    return dist_sq;
  }
  std::vector<Eigen::Vector3f> points;
  Adaptor adaptor;
  std::unique_ptr<Index> index;
};

namespace {
const PointKdTree& tree_of(const ObjectInstance& instance) {
  if (!instance.tree) instance.tree = std::make_shared<PointKdTree>(instance.points);
  return *instance.tree;
}
}  // namespace

/// The values at the trim_fraction and 1 - trim_fraction quantiles (exact min / max at 0).
std::pair<double, double> trimmed_range(std::vector<double>& v, double trim_fraction) {
  const size_t n = v.size(), k = std::min(n - 1, static_cast<size_t>(trim_fraction * static_cast<double>(n)));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  const double lo = v[k];
  std::nth_element(v.begin(), v.begin() + (n - 1 - k), v.end());
  return {lo, v[n - 1 - k]};
}

std::vector<Eigen::Vector3f> largest_cluster(const std::vector<Eigen::Vector3f>& points, double link_distance) {
  if (!(link_distance > 0) || points.size() < 2) return points;
  // Connected components of occupied cells (26-neighbourhood), then the points of the largest.
  auto key = [](const Eigen::Vector3i& c) {
    return (static_cast<uint64_t>(c.x() + (1 << 20)) << 42) | (static_cast<uint64_t>(c.y() + (1 << 20)) << 21) |
           static_cast<uint64_t>(c.z() + (1 << 20));
  };
  std::vector<Eigen::Vector3i> cell_of(points.size());
  std::unordered_map<uint64_t, int> component;  // cell -> component (-1 = not yet visited)
  for (size_t i = 0; i < points.size(); ++i) {
    cell_of[i] = (points[i].cast<double>() / link_distance).array().floor().cast<int>();
    component.emplace(key(cell_of[i]), -1);
  }
  int components = 0;
  std::vector<Eigen::Vector3i> stack;
  for (size_t i = 0; i < points.size(); ++i) {
    if (component[key(cell_of[i])] >= 0) continue;
    const int id = components++;
    component[key(cell_of[i])] = id;
    stack.assign(1, cell_of[i]);
    while (!stack.empty()) {
      const Eigen::Vector3i c = stack.back();
      stack.pop_back();
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const auto it = component.find(key(c + Eigen::Vector3i(dx, dy, dz)));
            if (it == component.end() || it->second >= 0) continue;
            it->second = id;
            stack.push_back(c + Eigen::Vector3i(dx, dy, dz));
          }
    }
  }
  std::vector<size_t> points_per_component(static_cast<size_t>(components), 0);
  for (size_t i = 0; i < points.size(); ++i) ++points_per_component[component[key(cell_of[i])]];
  const int best = static_cast<int>(std::max_element(points_per_component.begin(), points_per_component.end()) -
                                    points_per_component.begin());
  std::vector<Eigen::Vector3f> out;
  out.reserve(points_per_component[best]);
  for (size_t i = 0; i < points.size(); ++i)
    if (component[key(cell_of[i])] == best) out.push_back(points[i]);
  return out;
}

Eigen::AlignedBox3f trimmed_box(const std::vector<Eigen::Vector3f>& points, double trim_fraction) {
  Eigen::AlignedBox3f box;
  if (points.empty()) return box;
  std::vector<double> coordinate(points.size());
  for (int a = 0; a < 3; ++a) {
    for (size_t i = 0; i < points.size(); ++i) coordinate[i] = points[i][a];
    const auto [lo, hi] = trimmed_range(coordinate, trim_fraction);
    box.min()[a] = static_cast<float>(lo);
    box.max()[a] = static_cast<float>(hi);
  }
  return box;
}

std::vector<double> evidence_shares(const std::vector<double>& score_sum) {
  std::vector<double> shares(score_sum.size(), 0.0);
  double total = 0.0;
  for (double v : score_sum) total += std::max(0.0, v);
  if (!(total > 0.0)) return shares;
  for (size_t k = 0; k < score_sum.size(); ++k) shares[k] = std::max(0.0, score_sum[k]) / total;
  return shares;
}

ClassId evidence_class(const std::vector<double>& score_sum, double min_share) {
  const std::vector<double> shares = evidence_shares(score_sum);
  const auto it = std::max_element(shares.begin(), shares.end());
  if (it == shares.end() || !(*it > 0.0)) return 0;
  return *it >= min_share ? static_cast<ClassId>(it - shares.begin()) : id(Label::kOther);
}

std::vector<double> ObjectInstance::mean_scores() const { return augmented_mean_scores(score_sum, n); }

ObjectMap::ObjectMap(const ObjectsConfig& config) : config_(config) { config_.validate(); }

uint64_t ObjectMap::voxel_key(const Eigen::Vector3f& p) const {
  const double inv = 1.0 / config_.map_voxel_size;
  auto cell = [&](float x) { return static_cast<uint64_t>(static_cast<int64_t>(std::floor(x * inv)) + (1 << 20)) & 0x1FFFFF; };
  return (cell(p.x()) << 42) | (cell(p.y()) << 21) | cell(p.z());
}

void ObjectMap::add_points(ObjectInstance& instance, const std::vector<Eigen::Vector3f>& points,
                           const std::vector<Rgb8>& colours, const std::vector<uint32_t>& frames) {
  bool added = false;
  for (size_t i = 0; i < points.size(); ++i) {
    const auto [it, inserted] = instance.voxel_to_point.try_emplace(voxel_key(points[i]),
                                                                    static_cast<uint32_t>(instance.points.size()));
    if (!inserted) continue;
    instance.points.push_back(points[i]);
    instance.colours.push_back(i < colours.size() ? colours[i] : Rgb8{});
    instance.point_frames.push_back(frames.size() == points.size() ? frames[i] : (frames.empty() ? 0u : frames[0]));
    instance.point_sum += points[i].cast<double>();
    instance.bounds.extend(points[i]);
    added = true;
  }
  if (added) instance.tree.reset();
}

double ObjectMap::overlap(const std::vector<Eigen::Vector3f>& query, const ObjectInstance& instance,
                          double distance) const {
  if (query.empty() || instance.points.empty()) return 0.0;
  const PointKdTree& tree = tree_of(instance);
  const float limit_sq = static_cast<float>(distance * distance);
  size_t hits = 0;
  for (const auto& q : query)
    if (tree.nearest_sq(q) < limit_sq) ++hits;
  return static_cast<double>(hits) / static_cast<double>(query.size());
}

void ObjectMap::downsample(const ObjectSegment& segment, std::vector<Eigen::Vector3f>& points,
                           std::vector<Rgb8>& colours) const {
  std::unordered_map<uint64_t, char> seen;
  seen.reserve(segment.points.size());
  for (size_t i = 0; i < segment.points.size(); ++i) {
    if (!seen.try_emplace(voxel_key(segment.points[i]), 1).second) continue;
    points.push_back(segment.points[i]);
    colours.push_back(i < segment.colours.size() ? segment.colours[i] : Rgb8{});
  }
}

std::vector<std::pair<float, size_t>> ObjectMap::gate(const std::vector<Eigen::Vector3f>& points,
                                                      std::optional<ClassId> only_class) const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::AlignedBox3f box;
  for (const auto& p : points) sum += p.cast<double>(), box.extend(p);
  const Eigen::Vector3f centroid = (sum / static_cast<double>(points.size())).cast<float>();
  const float margin = static_cast<float>(config_.association_box_margin);
  const bool extent = config_.association_gate == AssociationGate::extent;
  std::vector<std::pair<float, size_t>> candidates;
  for (size_t j = 0; j < instances_.size(); ++j) {
    const ObjectInstance& inst = instances_[j];
    if (only_class && inst.class_id() != *only_class) continue;
    const float d = (inst.centroid() - centroid).norm();
    // Extension to C4 (extent gate): candidates are the instances the segment touches, whatever
    // their size; a large object seen in parts has its centroid far from a part's.
    const bool pass = extent ? !inst.bounds.isEmpty() && inst.bounds.exteriorDistance(box) <= margin
                             : d < config_.association_distance;
    if (pass) candidates.emplace_back(d, j);
  }
  std::sort(candidates.begin(), candidates.end());
  return candidates;
}

size_t ObjectMap::extend(const std::vector<ObjectSegment>& segments, size_t frame_index) {
  size_t extended = 0;
  for (const auto& segment : segments) {
    if (segment.points.empty()) continue;
    std::vector<Eigen::Vector3f> points;
    std::vector<Rgb8> colours;
    downsample(segment, points, colours);
    for (const auto& [d, j] : gate(points, segment.class_id)) {
      if (overlap(points, instances_[j], config_.overlap_distance) <= config_.overlap_ratio) continue;
      add_points(instances_[j], points, colours, {static_cast<uint32_t>(frame_index)});
      instances_[j].last_frame = std::max(instances_[j].last_frame, frame_index);
      ++extended;
      break;
    }
  }
  return extended;
}

void ObjectMap::associate(const std::vector<ObjectSegment>& segments, size_t frame_index, size_t step) {
  for (const auto& segment : segments) {
    if (segment.points.empty()) continue;
    // Downsample the segment to the map's voxels first: bounded cost per segment.
    std::vector<Eigen::Vector3f> points;
    std::vector<Rgb8> colours;
    downsample(segment, points, colours);
    // C4: candidates inside the gate, nearest first; with association_class_share only those
    // whose evidence admits the segment's class (a mug is no candidate of the table it is on,
    // so the table's association count says how often the table was seen).
    std::vector<std::pair<float, size_t>> candidates = gate(points, std::nullopt);
    std::erase_if(candidates, [&](const auto& c) { return !accepts_class(instances_[c.second], segment.class_id); });
    for (size_t a = 0; a < candidates.size(); ++a) {
      auto& inst = instances_[candidates[a].second];
      ++inst.association_count;
      ++inst.total_associations;
      for (size_t b = 0; b < candidates.size(); ++b)
        if (a != b) ++inst.co_association[instances_[candidates[b].second].id];
    }
    // Extension (config reverse_containment): the segment covers most of an instance of its
    // own class. Without it a first small glimpse of an object and the fuller later views
    // become duplicates whenever the later view is mostly new surface.
    std::unique_ptr<PointKdTree> segment_tree;
    auto segment_covers = [&](const ObjectInstance& inst) {
      if (!config_.reverse_containment || inst.class_id() != segment.class_id || inst.points.empty()) return false;
      if (!segment_tree) segment_tree = std::make_unique<PointKdTree>(points);
      const float limit_sq = static_cast<float>(config_.overlap_distance * config_.overlap_distance);
      size_t hits = 0;
      for (const auto& p : inst.points)
        if (segment_tree->nearest_sq(p) < limit_sq) ++hits;
      return hits > config_.reverse_containment_ratio * inst.points.size();
    };
    // C4 target: the candidate the segment overlaps most, above r (the paper takes the nearest
    // candidate above r; with the extent gate a large object's centroid may be the farthest).
    size_t target = instances_.size();
    double best_overlap = config_.overlap_ratio;
    std::vector<char> covers(instances_.size(), 0);
    for (const auto& [d, j] : candidates) {
      covers[j] = segment_covers(instances_[j]);
      const double o = overlap(points, instances_[j], config_.overlap_distance);
      if (o > best_overlap) target = j, best_overlap = o;
    }
    if (target == instances_.size())
      for (const auto& [d, j] : candidates)
        if (covers[j]) { target = j; break; }
    std::vector<size_t> covered;  // further same-class instances this segment covers: duplicates
    for (const auto& [d, j] : candidates)
      if (j != target && covers[j]) covered.push_back(j);
    if (target == instances_.size()) {
      instances_.emplace_back();
      auto& created = instances_.back();
      created.id = next_id_++;
      created.score_sum.assign(kNumClasses, 0.0);
      created.first_frame = frame_index;
      created.association_count = 1;
      created.total_associations = 1;
      // The new instance was co-candidate with every candidate of its creating segment (C5).
      for (const auto& [d, j] : candidates) {
        ++instances_[j].co_association[created.id];
        ++created.co_association[instances_[j].id];
      }
    }
    ObjectInstance& inst = instances_[target];
    add_points(inst, points, colours, {static_cast<uint32_t>(frame_index)});
    inst.n += 1;
    add_scores(inst, segment.class_scores);
    inst.last_frame = std::max(inst.last_frame, frame_index);
    inst.last_step = step;
    inst.changed = true;
    if (!covered.empty()) {
      for (size_t j : covered) merge_into(inst, instances_[j]);
      std::sort(covered.rbegin(), covered.rend());
      for (size_t j : covered) {
        const uint32_t gone = instances_[j].id;
        instances_.erase(instances_.begin() + static_cast<std::ptrdiff_t>(j));
        for (auto& other : instances_) other.co_association.erase(gone);
      }
    }
  }
}

void ObjectMap::apply_pose_corrections(const std::unordered_map<uint32_t, Eigen::Isometry3f>& corrections) {
  for (auto& inst : instances_) {
    std::vector<Eigen::Vector3f> points = std::move(inst.points);
    std::vector<Rgb8> colours = std::move(inst.colours);
    std::vector<uint32_t> frames = std::move(inst.point_frames);
    inst.points.clear();
    inst.colours.clear();
    inst.point_frames.clear();
    inst.voxel_to_point.clear();
    inst.point_sum.setZero();
    inst.bounds.setEmpty();
    for (size_t i = 0; i < points.size(); ++i) {
      const auto it = corrections.find(frames[i]);
      if (it != corrections.end()) points[i] = it->second * points[i];
    }
    add_points(inst, points, colours, frames);
    inst.tree.reset();
  }
}

std::vector<double> ObjectMap::label_distribution(const ObjectInstance& instance) const {
  return config_.merge_distribution == MergeDistribution::augmented ? instance.mean_scores()
                                                                     : evidence_shares(instance.score_sum);
}

bool ObjectMap::accepts_class(const ObjectInstance& instance, ClassId cls) const {
  if (config_.association_class_share <= 0.0) return true;
  const double total = std::accumulate(instance.score_sum.begin(), instance.score_sum.end(), 0.0);
  if (!(total > 0.0) || cls >= instance.score_sum.size()) return true;
  return instance.score_sum[cls] >= config_.association_class_share * total;
}

double ObjectMap::label_divergence(const ObjectInstance& a, const ObjectInstance& b) const {
  return js_divergence(label_distribution(a), label_distribution(b));
}

void ObjectMap::add_scores(ObjectInstance& instance, const std::vector<double>& scores) {
  for (size_t k = 0; k < instance.score_sum.size() && k < scores.size(); ++k) instance.score_sum[k] += scores[k];
  instance.decided_class = evidence_class(instance.score_sum, config_.class_min_share);
}

void ObjectMap::merge_into(ObjectInstance& target, ObjectInstance& source) {
  add_points(target, source.points, source.colours, source.point_frames);
  target.n += source.n;
  add_scores(target, source.score_sum);
  target.association_count = std::max(target.association_count, source.association_count);
  target.total_associations += source.total_associations;
  target.first_frame = std::min(target.first_frame, source.first_frame);
  target.last_frame = std::max(target.last_frame, source.last_frame);
  target.last_step = std::max(target.last_step, source.last_step);
  for (const auto& [id, count] : source.co_association)
    if (id != target.id) target.co_association[id] = std::max(target.co_association[id], count);
  target.co_association.erase(source.id);
  target.changed = true;
}

void ObjectMap::absorb_fragment(size_t i, const std::vector<char>& remove, OptimisationStats& stats) {
  // A rarely seen instance that lies on a STABLE one of the same class distribution is a partial
  // view of it (its segment just missed the C4 overlap ratio), not a false detection: its
  // surface joins that instance instead of being thrown away. Same overlap (3) and JS (4)
  // tests as the C5 merge.
  const ObjectInstance& inst = instances_[i];
  size_t best = instances_.size();
  double best_overlap = config_.merge_overlap_ratio;
  for (size_t j = 0; j < instances_.size(); ++j) {
    if (j == i || remove[j] || instances_[j].state != InstanceState::kStable) continue;
    if ((instances_[j].centroid() - inst.centroid()).norm() >= config_.association_distance) continue;
    const double o = overlap(inst.points, instances_[j], config_.overlap_distance);
    if (o >= best_overlap && label_divergence(inst, instances_[j]) <= config_.merge_max_js)
      best = j, best_overlap = o;
  }
  if (best == instances_.size()) return;
  // Only the points: the fragment's counts are those of a rejected instance (C5 keeps the
  // target's class evidence as it was).
  add_points(instances_[best], inst.points, inst.colours, inst.point_frames);
  ++stats.absorbed;
}

void ObjectMap::promote_or_delete(size_t step, bool ignore_recency, std::vector<char>& remove,
                                  OptimisationStats& stats) {
  // T of the deletion rule s_i + n_i < T/10 (METHODS C5): the optimisation period, or the whole
  // run when it is shorter (the final pass of a run of 2 object frames cannot ask an instance
  // for the counts 50 frames would give; a late fragment of a long run still goes).
  const double T = static_cast<double>(std::min<size_t>(step, config_.optimise_every));
  for (size_t i = 0; i < instances_.size(); ++i) {
    auto& inst = instances_[i];
    if (inst.state == InstanceState::kStable) continue;
    const bool recent = !ignore_recency && step - inst.last_step <= static_cast<size_t>(config_.recent_frames);
    if (inst.association_count >= config_.stable_min_associations) {
      inst.state = InstanceState::kStable;
      ++stats.promoted;
    } else if (config_.enable_delete && inst.association_count + inst.n < config_.delete_fraction * T && !recent) {
      remove[i] = 1;
      ++stats.deleted;
      if (config_.absorb_fragments) absorb_fragment(i, remove, stats);
    } else {
      inst.state = InstanceState::kUnstable;
    }
  }
}

bool ObjectMap::geometric_overlap(const ObjectInstance& a, const ObjectInstance& b) const {
  const bool a_smaller = a.points.size() <= b.points.size();
  const ObjectInstance& small = a_smaller ? a : b;
  const ObjectInstance& large = a_smaller ? b : a;
  if (overlap(small.points, large, config_.overlap_distance) >= config_.merge_overlap_ratio) return true;
  if (config_.merge_containment_ratio >= 1.0 || small.points.empty()) return false;
  Eigen::AlignedBox3f box = trimmed_box(largest_cluster(large.points, config_.merge_body_link_distance), config_.box_trim_fraction);
  const Eigen::Vector3f grow = Eigen::Vector3f::Constant(static_cast<float>(config_.overlap_distance));
  box.extend(box.min() - grow).extend(box.max() + grow);
  size_t inside = 0;
  for (const auto& p : small.points) inside += box.contains(p);
  return inside >= config_.merge_containment_ratio * static_cast<double>(small.points.size());
}

void ObjectMap::merge_stable_pairs(std::vector<char>& remove, OptimisationStats& stats) {
  bool merged_any = true;
  while (merged_any) {
    merged_any = false;
    for (size_t i = 0; i < instances_.size() && !merged_any; ++i) {
      if (remove[i] || instances_[i].state != InstanceState::kStable) continue;
      for (size_t j = i + 1; j < instances_.size(); ++j) {
        auto& a = instances_[i];
        auto& b = instances_[j];
        if (remove[j] || b.state != InstanceState::kStable) continue;  // (1)
        if (!a.changed && !b.changed) continue;  // only re-check instances whose counts changed
        const auto co_it = a.co_association.find(b.id);
        const int co = co_it == a.co_association.end() ? 0 : co_it->second;
        // (2): "exceeds a fraction of either one's association count" read as: of at least one.
        const int s_min = std::min(a.association_count, b.association_count);
        if (co <= 0 || co <= config_.merge_coassociation * s_min) continue;
        ++stats.pairs_checked;
        if (!geometric_overlap(a, b)) continue;                                               // (3)
        if (label_divergence(a, b) > config_.merge_max_js) continue;  // (4)
        // Keep the instance with more merges (its id is the better established one).
        const bool keep_a = a.n >= b.n;
        merge_into(keep_a ? a : b, keep_a ? b : a);
        remove[keep_a ? j : i] = 1;
        ++stats.merged;
        merged_any = true;
        break;
      }
    }
  }
}

int ObjectMap::merge_target(const ObjectInstance& inst) const {
  int best = -1;
  double best_overlap = -1.0;
  for (size_t j = 0; j < instances_.size(); ++j) {
    const ObjectInstance& here = instances_[j];
    if (!geometric_overlap(inst, here) || label_divergence(inst, here) > config_.merge_max_js) continue;  // (3), (4)
    const double o = overlap(inst.points, here, config_.overlap_distance);
    if (o > best_overlap) best = static_cast<int>(j), best_overlap = o;
  }
  return best;
}

ObjectMapMergeCounts ObjectMap::merge_map(const ObjectMap& other, const Eigen::Isometry3f& T_this_other) {
  ObjectMapMergeCounts counts;
  for (const ObjectInstance& source : other.instances()) {
    ObjectInstance moved = source;
    moved.points.clear(), moved.colours.clear(), moved.point_frames.clear(), moved.voxel_to_point.clear();
    moved.point_sum.setZero();
    moved.bounds.setEmpty();
    moved.tree.reset();
    moved.co_association.clear();  // the other map's ids
    std::vector<Eigen::Vector3f> points;
    points.reserve(source.points.size());
    for (const auto& p : source.points) points.push_back(T_this_other * p);
    add_points(moved, points, source.colours, {kSavedMapFrame});
    const int target = merge_target(moved);
    if (target >= 0) {
      ObjectInstance& into = instances_[static_cast<size_t>(target)];
      moved.id = 0;  // merge_into must not match it against into's co-association ids
      merge_into(into, moved);
      into.state = std::max(into.state, moved.state);
      counts.ids[source.id] = into.id;
      ++counts.merged;
    } else {
      moved.id = next_id_++;
      counts.ids[source.id] = moved.id;
      instances_.push_back(std::move(moved));
      ++counts.added;
    }
  }
  return counts;
}

OptimisationStats ObjectMap::optimise(size_t step, bool ignore_recency) {
  OptimisationStats stats;
  stats.before = instances_.size();
  std::vector<char> remove(instances_.size(), 0);
  promote_or_delete(step, ignore_recency, remove, stats);  // NEW / UNSTABLE (C5)
  stats.after_delete = stats.before - static_cast<size_t>(stats.deleted);
  if (config_.enable_merge) merge_stable_pairs(remove, stats);  // STABLE pairs (C5)
  stats.after_merge = stats.after_delete - static_cast<size_t>(stats.merged);
  std::vector<ObjectInstance> kept;
  kept.reserve(instances_.size());
  for (size_t i = 0; i < instances_.size(); ++i)
    if (!remove[i]) kept.push_back(std::move(instances_[i]));
  instances_ = std::move(kept);
  for (auto& inst : instances_) {
    inst.association_count = 0;
    inst.co_association.clear();
    inst.changed = false;
  }
  return stats;
}

std::vector<uint32_t> ObjectMap::instance_ids_for(const std::vector<Eigen::Vector3f>& points, float max_dist) const {
  std::vector<uint32_t> ids(points.size(), 0);
  std::vector<Eigen::Vector3f> all;
  std::vector<uint32_t> owner;
  for (const auto& inst : instances_) {
    all.insert(all.end(), inst.points.begin(), inst.points.end());
    owner.insert(owner.end(), inst.points.size(), inst.id);
  }
  if (all.empty()) return ids;
  const PointKdTree tree(std::move(all));
  const float limit_sq = max_dist * max_dist;
  for (size_t i = 0; i < points.size(); ++i) {
    size_t which = 0;
    if (tree.nearest_sq(points[i], &which) <= limit_sq) ids[i] = owner[which];
  }
  return ids;
}

}  // namespace semap
