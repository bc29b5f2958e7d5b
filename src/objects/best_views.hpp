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
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "objects/object_map.hpp"
#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"
#include "semap/core/pose.hpp"

namespace semap {

/// Longest side of a kept crop, pixels (the report shows cards of 96 px).
inline constexpr int kBestViewMaxSidePx = 96;

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

 private:
  struct View {
    double score = 0.0;
    std::string jpeg;
  };
  PinholeIntrinsics camera_;
  std::unordered_map<uint32_t, View> views_;
};

}  // namespace semap
