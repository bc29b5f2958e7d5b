#pragma once
// The object map (METHODS.md C3), association of frame segments (C4) and the optimisation by
// association counts (C5).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>
#include <optional>
#include <utility>
#include <vector>

#include "semap/core/labels.hpp"
#include "objects/frame_segmenter.hpp"
#include "semap/objects/objects_config.hpp"

namespace semap {

enum class InstanceState { kNew, kUnstable, kStable };
const char* state_name(InstanceState state);

struct PointKdTree;  // nanoflann index, defined in object_map.cpp

/// o_i = <n_i, c_i, P_i> plus what C5 needs.
struct ObjectInstance {
  uint32_t id = 0;
  int n = 0;                          ///< merge count: segments merged in
  std::vector<double> score_sum;      ///< c_i, accumulated class scores, size kNumClasses
  std::vector<Eigen::Vector3f> points;  ///< P_i, world frame, one per occupied map voxel
  std::vector<Rgb8> colours;
  std::vector<uint32_t> point_frames;  ///< per point: the frame it was observed in (pose corrections)
  Eigen::Vector3d point_sum = Eigen::Vector3d::Zero();
  Eigen::AlignedBox3f bounds;         ///< axis-aligned box of the points (empty when none)
  ClassId decided_class = 0;          ///< evidence_class(score_sum), updated with the scores
  int association_count = 0;          ///< s_i since the last optimisation
  int total_associations = 0;         ///< s_i over the whole run (reporting)
  std::unordered_map<uint32_t, int> co_association;  ///< co-candidacy with other ids since the last optimisation
  size_t first_frame = 0, last_frame = 0;  ///< frame indices (reporting)
  size_t last_step = 0;               ///< process() call that last merged a segment (recency)
  InstanceState state = InstanceState::kNew;
  bool changed = true;                ///< merge count changed since the last optimisation
  std::unordered_map<uint64_t, uint32_t> voxel_to_point;
  mutable std::shared_ptr<PointKdTree> tree;  ///< rebuilt lazily after points change

  Eigen::Vector3f centroid() const {
    if (points.empty()) return Eigen::Vector3f::Zero();
    return (point_sum / static_cast<double>(points.size())).cast<float>();
  }
  /// The class decided by the evidence over frames (evidence_class); 0 only without scores.
  ClassId class_id() const { return decided_class; }
  /// Augmented mean score vector (C5).
  std::vector<double> mean_scores() const;
};

/// The class an instance's accumulated scores support (C3): the argmax class when it holds at
/// least `min_share` of the class evidence (the scores summed over its segments, detector
/// uncertainty left out), else `other`: an object the detector called a table in a third of
/// its views and something else in the rest is not a table. 0 when there is no evidence.
ClassId evidence_class(const std::vector<double>& score_sum, double min_share);
/// Share of each class in the evidence (sums to 1; all 0 without evidence).
std::vector<double> evidence_shares(const std::vector<double>& score_sum);

/// The values at the trim_fraction and 1 - trim_fraction quantiles of `v` (exact min / max at 0);
/// reorders `v`.
std::pair<double, double> trimmed_range(std::vector<double>& v, double trim_fraction);
/// The points of the largest cluster whose members are linked by chains of neighbours closer than
/// about `link_distance` (cells of that size, 26-connected). Stray points that bled into an
/// instance across a depth edge form their own small clusters and are left out.
std::vector<Eigen::Vector3f> largest_cluster(const std::vector<Eigen::Vector3f>& points, double link_distance);
/// Axis-aligned box of the points with `trim_fraction` of them ignored at each end of every axis.
Eigen::AlignedBox3f trimmed_box(const std::vector<Eigen::Vector3f>& points, double trim_fraction);

struct ObjectMapMergeCounts {
  size_t merged = 0;  ///< instances of the other map folded into one of this map
  size_t added = 0;   ///< instances of the other map added as new objects
  std::unordered_map<uint32_t, uint32_t> ids;  ///< other map's instance id -> the id it has here
};

struct OptimisationStats {
  size_t before = 0, after_delete = 0, after_merge = 0;  ///< instances in the map around each C5 step
  int promoted = 0, deleted = 0, merged = 0, pairs_checked = 0;
  int absorbed = 0;  ///< deleted instances whose points joined a stable one (absorb_fragments)
};

class ObjectMap {
 public:
  explicit ObjectMap(const ObjectsConfig& config);

  /// C4: associates each segment with the map (merge or create). `step` counts process() calls.
  void associate(const std::vector<ObjectSegment>& segments, size_t frame_index, size_t step);
  /// Extension to C3 (accumulate_between_keyframes): each segment's points join the nearest
  /// candidate instance of its class that passes the C4 overlap test; nothing is created and
  /// no count (n, c, s, co-association) changes, so C5 still sees keyframes only.
  /// Returns the number of segments whose points were added.
  size_t extend(const std::vector<ObjectSegment>& segments, size_t frame_index);
  /// Moves every instance point by the correction of the frame it was observed in (e.g. the
  /// pose-graph update after a loop closure: T_optimised * T_online^-1); points of frames
  /// without a correction stay. Points landing in one map voxel merge (C3).
  void apply_pose_corrections(const std::unordered_map<uint32_t, Eigen::Isometry3f>& corrections);
  /// C5: promote / delete / merge, then reset association counts. `ignore_recency` drops the
  /// "seen recently" exemption (final pass).
  OptimisationStats optimise(size_t step, bool ignore_recency);

  const std::vector<ObjectInstance>& instances() const { return instances_; }
  /// Instances created so far (C4 "no target"), before any C5 deletion or merge.
  size_t created() const { return next_id_ - 1; }
  /// Fraction of `query` points with an instance point closer than `distance` (C4 overlap).
  double overlap(const std::vector<Eigen::Vector3f>& query, const ObjectInstance& instance, double distance) const;
  /// Per point: id of the instance with the nearest point within max_dist, else 0.
  std::vector<uint32_t> instance_ids_for(const std::vector<Eigen::Vector3f>& points, float max_dist) const;

  /// Map merging (issue 19): the instances of `other` (another recording's map of the same
  /// place), moved into this map's frame by T_this_other, join this map. One that C5's tests
  /// (3) geometric overlap and (4) JS divergence pair with an instance here merges into the one
  /// it overlaps most (the evidence of both: points, class scores, merge and association
  /// counts); the others are added with new ids. C5's test (2), co-association, has no meaning
  /// across recordings: the common frame's overlap stands in for it.
  ObjectMapMergeCounts merge_map(const ObjectMap& other, const Eigen::Isometry3f& T_this_other);

  /// Key of the map voxel (map_voxel_size) holding `p`: an instance has one point per key.
  uint64_t voxel_key(const Eigen::Vector3f& p) const;

  /// Frame of the points of a map saved by an earlier run: no pose correction moves them.
  static constexpr uint32_t kSavedMapFrame = 0xFFFFFFFFu;
  /// The instances as a map.semap section (issue 19; src/objects/object_map_io.cpp).
  std::string encode_state() const;
  /// Replaces the instances with a saved section's; their points' frames become kSavedMapFrame.
  /// Throws semap::Error naming `path` for a corrupt section.
  void decode_state(std::string_view bytes, const std::filesystem::path& path);

 private:
  /// One point per map voxel of the segment (the first), with its colour.
  void downsample(const ObjectSegment& segment, std::vector<Eigen::Vector3f>& points, std::vector<Rgb8>& colours) const;
  /// `frames`: per point, or one entry for all of them.
  void add_points(ObjectInstance& instance, const std::vector<Eigen::Vector3f>& points, const std::vector<Rgb8>& colours,
                  const std::vector<uint32_t>& frames);
  void merge_into(ObjectInstance& target, ObjectInstance& source);
  /// Extension to C4 (association_class_share): the instance's evidence gives `cls` enough share
  /// for a segment of that class to merge into it.
  bool accepts_class(const ObjectInstance& instance, ClassId cls) const;
  /// The distribution C5 test (4) compares (config merge_distribution).
  std::vector<double> label_distribution(const ObjectInstance& instance) const;
  double label_divergence(const ObjectInstance& a, const ObjectInstance& b) const;
  /// Adds a segment's class scores to the instance's evidence and re-decides its class.
  void add_scores(ObjectInstance& instance, const std::vector<double>& scores);
  /// C5 test (3): the smaller instance's points lie on the larger's surface (C4 overlap) or,
  /// extension, inside the box of its body (two views of an object from opposite sides share no
  /// surface). The body box (largest cluster, trimmed as the exported boxes) ignores the stray
  /// points a bleeding mask leaves: with the raw box one such cluster 30 cm into a touching
  /// neighbour made the two one object.
  bool geometric_overlap(const ObjectInstance& a, const ObjectInstance& b) const;
  /// C5 promote / delete pass over NEW and UNSTABLE instances; marks deletions in `remove`.
  void promote_or_delete(size_t step, bool ignore_recency, std::vector<char>& remove, OptimisationStats& stats);
  /// Extension (absorb_fragments): the deleted instance i's points join a stable one it overlaps.
  void absorb_fragment(size_t i, const std::vector<char>& remove, OptimisationStats& stats);
  /// The instance here that `inst` overlaps most and passes C5 tests (3) and (4) with, or -1.
  int merge_target(const ObjectInstance& inst) const;
  /// C5 merge of stable pairs (tests 1-4), until no pair merges.
  void merge_stable_pairs(std::vector<char>& remove, OptimisationStats& stats);
  /// C4 gate (config association_gate): (centroid distance, index) of the instances whose
  /// centroid is within association_distance of the centroid of `points`, or whose box grown by
  /// association_box_margin meets the points' box; nearest first; only_class keeps that class.
  std::vector<std::pair<float, size_t>> gate(const std::vector<Eigen::Vector3f>& points,
                                             std::optional<ClassId> only_class) const;

  ObjectsConfig config_;
  std::vector<ObjectInstance> instances_;
  uint32_t next_id_ = 1;
};

}  // namespace semap
