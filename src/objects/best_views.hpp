#pragma once
// The view of each object to show a person (issue 43: the report's object cards): per object,
// a small crop of the keyframe that saw it best so far, replaced when a better view comes.
//
// A view's score is the object's unoccluded projected area in the frame: the pixel area of the
// box around its points that project inside the image and agree with the frame's depth (not
// hidden behind something nearer), times the share of its points that do. A view that cuts the
// object at the image border or hides half of it behind a chair scores low.
//
// Memory is bounded: one JPEG of at most kBestViewMaxSidePx a side (a few KB) per object alive
// in the map; views of objects that left the map (C5 delete / merge) are dropped.
//
// The views are kept in map.semap as their own section (kObjectViewsSection), so that a resumed
// or merged map's objects keep their report thumbnails:
//   u32 format | u64 view count | per view (ascending object id): u32 object id, f64 score,
//   u64 keyframe index, u64 JPEG bytes (<= kBestViewMaxJpegBytes), the JPEG
// A map written before the section existed loads with no views.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "objects/object_map.hpp"
#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"
#include "semap/core/pose.hpp"

namespace semap {

/// Longest side of a kept crop, pixels (the report shows cards of 96 px).
inline constexpr int kBestViewMaxSidePx = 96;
/// Largest JPEG kept (and read back from map.semap) per object, bytes. A 96 x 96 crop at the
/// kept quality is a few KB; pure noise, JPEG's worst case, 7.6 KB: 32 KB leaves room and
/// bounds what a corrupt file makes the reader allocate. A larger encoding is not kept.
inline constexpr size_t kBestViewMaxJpegBytes = size_t{32} << 10;
/// Name of the best views' map.semap section (optional: older maps have none).
inline constexpr const char* kObjectViewsSection = "object_views";

/// Not thread-safe: the object map's thread updates it (ObjectMapper::process), readers hold
/// the same lock.
class BestViews {
 public:
  explicit BestViews(const PinholeIntrinsics& depth_camera) : camera_(depth_camera) {}
  /// Scores this keyframe's view of every instance (frame.depth in metres; frame.rgb BGR,
  /// registered to depth) and keeps the crop where it beats the one kept; forgets the views of
  /// ids no longer among `instances`. A frame without colour changes nothing.
  void update(const std::vector<ObjectInstance>& instances, const Frame& frame, const Pose& T_world_camera);
  /// The kept JPEG of object `id`; empty when none.
  std::string jpeg(uint32_t id) const;
  size_t bytes() const;  ///< memory held by the crops
  size_t size() const { return views_.size(); }  ///< objects with a view
  const PinholeIntrinsics& camera() const { return camera_; }

  /// Forgets the views of ids no longer among `instances` (update does it too; a C5 pass after
  /// the last keyframe, ObjectMapper::finish, needs it).
  void forget_all_but(const std::vector<ObjectInstance>& instances);
  /// The views of `instances` (the object map's, as saved beside them) as the
  /// kObjectViewsSection payload: ascending ids, so equal views give equal bytes.
  std::string encode(const std::vector<ObjectInstance>& instances) const;
  /// Replaces the views by those of a kObjectViewsSection payload. Every view must belong to one
  /// of `alive_ids` (the restored object map's); a malformed payload throws Error(path, ...).
  void decode(std::string_view bytes, const std::filesystem::path& path, const std::vector<uint32_t>& alive_ids);
  /// Map merging: the views of another map whose object `other_id` became `ids[other_id]` here
  /// (ObjectMapMergeCounts::ids); where both maps saw an object the better view (score) stays.
  void merge(const BestViews& other, const std::unordered_map<uint32_t, uint32_t>& ids);

 private:
  /// What decides replacement: the score (unoccluded projected area, depth pixels) of the
  /// keyframe the crop came from.
  struct View {
    double score = 0.0;
    uint64_t keyframe_index = 0;  ///< Frame::index of that keyframe, in the recording that saw it
    std::string jpeg;
  };
  PinholeIntrinsics camera_;
  std::unordered_map<uint32_t, View> views_;
};

}  // namespace semap
