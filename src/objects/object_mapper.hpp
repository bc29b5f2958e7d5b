#pragma once
// The object-oriented map of seed 000 (METHODS.md C2-C5): per keyframe, mask-guided segments
// are associated with the map; every T frames the map is optimised by association counts.
#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <nlohmann/json.hpp>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"
#include "objects/best_views.hpp"
#include "objects/frame_segmenter.hpp"
#include "objects/object_map.hpp"
#include "semap/objects/object_summary.hpp"
#include "semap/objects/objects_config.hpp"
#include "semap/segmentation/segmenter.hpp"

namespace semap {

struct ObjectMapperTimings {
  double segmentation_ms = 0.0;  ///< C2, summed over process() calls
  double association_ms = 0.0;   ///< C4 + C5, summed
  double accumulation_ms = 0.0;  ///< accumulate() calls, summed (back-projection + extend)
  double best_views_ms = 0.0;    ///< BestViews::update (view scoring + JPEG encoding), summed
  size_t frames = 0;
  size_t accumulated_frames = 0;
  size_t optimisations = 0;
};

/// What C5 did over the run: instances created by association (C4), then removed by each step.
struct ObjectMapCounts {
  size_t created = 0;   ///< instances created (C4)
  size_t deleted = 0;   ///< C5 deletions (too few associations)
  size_t absorbed = 0;  ///< of those, whose points joined a stable instance (absorb_fragments)
  size_t merged = 0;    ///< C5 merges of stable pairs
  size_t covered = 0;   ///< folded into a segment that covered them at association (reverse_containment)
  size_t final = 0;     ///< instances at the end
};

/// Name of the object map's map.semap section (ObjectMapper::encode_state).
inline constexpr const char* kObjectsSection = "objects";

class ObjectMapper {
 public:
  ObjectMapper(const ObjectsConfig& config, const CameraModel& camera);
  /// One keyframe: C2 segments -> C4 association; C5 every optimise_every calls; then each
  /// object's best view so far (objects/best_views.hpp, ObjectSummary::best_view_jpeg).
  void process(const Frame& frame, const SegmentationResult& segmentation, const Pose& T_world_camera);
  /// A segmented frame that is not an object keyframe (config accumulate_between_keyframes;
  /// a no-op when off): its masks, back-projected, add points to the instances they overlap
  /// (ObjectMap::extend). The keyframes alone decide instances and counts (C2, C4, C5).
  void accumulate(const Frame& frame, const SegmentationResult& segmentation, const Pose& T_world_camera);
  bool accumulates() const { return config_.accumulate_between_keyframes; }
  /// Per frame index: T_optimised * T_online^-1 (see ObjectMap::apply_pose_corrections).
  void apply_pose_corrections(const std::unordered_map<uint32_t, Eigen::Isometry3f>& corrections) {
    map_.apply_pose_corrections(corrections);
  }
  /// Final C5 pass (config final_optimisation). Call once after the last frame.
  void finish();
  /// The objects.json document.
  nlohmann::json to_json() const;  ///< of summaries() without surface projection
  /// The fused surface at given points (the Mapper passes the TSDF's): each point moved onto it,
  /// and the class the map shows there (0 = none). Used for the exported points when config
  /// points_on_surface (and drop_points_of_other_classes).
  struct SurfaceSamples {
    std::vector<Eigen::Vector3f> points;
    std::vector<ClassId> labels;  ///< same size as points
  };
  using SurfaceProjection = std::function<SurfaceSamples(const std::vector<Eigen::Vector3f>&)>;
  /// Every non-empty instance, with its box and class distribution.
  std::vector<ObjectSummary> summaries(const SurfaceProjection& onto_surface = {}) const;

  const std::vector<ObjectInstance>& instances() const { return map_.instances(); }
  const ObjectMap& map() const { return map_; }
  /// Per point: id of the object with a point within max_dist (metres), else 0 (mesh labelling).
  std::vector<uint32_t> instance_ids_for(const std::vector<Eigen::Vector3f>& points, float max_dist) const {
    return map_.instance_ids_for(points, max_dist);
  }
  const ObjectMapperTimings& timings() const { return timings_; }
  const std::vector<OptimisationStats>& optimisation_log() const { return optimisation_log_; }
  /// Created / deleted / merged over the run (from the optimisation log).
  ObjectMapCounts counts() const;
  /// The object map and the C5 step count as a map.semap section (issue 19).
  std::string encode_state() const;
  /// Continues a saved object map: its instances (fixed points, their counts and states) and
  /// step count; objects seen again associate with them (C4). Call before the first frame.
  void restore_state(std::string_view bytes, const std::filesystem::path& path);
  /// Map merging (issue 19): the saved object map `bytes` of another recording, moved by
  /// T_this_other, joins this one (ObjectMap::merge_map); with its best views (`views_bytes`,
  /// its kObjectViewsSection; null when its map has none), which follow its objects' new ids.
  ObjectMapMergeCounts merge_state(std::string_view bytes, const std::filesystem::path& path,
                                   const Eigen::Isometry3f& T_this_other, const std::string* views_bytes = nullptr);
  /// Each object's best view as the kObjectViewsSection payload (objects/best_views.hpp).
  std::string encode_views() const { return best_views_.encode(map_.instances()); }
  /// The saved best views of the restored objects; call after restore_state (their ids).
  void restore_views(std::string_view bytes, const std::filesystem::path& path);
  const BestViews& best_views() const { return best_views_; }

 private:
  ObjectsConfig config_;
  FrameSegmenter segmenter_;
  ObjectMap map_;
  BestViews best_views_;
  size_t step_ = 0;
  ObjectMapperTimings timings_;
  std::vector<OptimisationStats> optimisation_log_;
  bool finished_ = false;
};

/// `trim_fraction` of the points is ignored at each end of every box axis (0 = exact hull).
OrientedBox fit_oriented_box(const std::vector<Eigen::Vector3f>& points, double trim_fraction = 0.0);

/// Which exported points to leave out (ObjectsConfig::drop_points_of_other_classes): those the
/// fused map labels as another class than `class_id` (0 = no label), when they are a minority.
/// A mask that bled over a neighbour in some frames left that neighbour's points in the
/// instance, while the TSDF's label of each voxel weighs every frame (METHODS A6). A majority
/// that disagrees says the object's class is in doubt, not where its surface is: none is left out.
std::vector<bool> points_of_other_classes(const std::vector<ClassId>& surface_labels, ClassId class_id);

}  // namespace semap
