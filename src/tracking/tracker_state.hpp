#pragma once
// The tracker's keyframe database and pose graph as a map.semap section (issue 19): what a
// later recording needs to relocalise into this map (METHODS.md A3) and to extend its graph (A4).
//   u32 format | u64 keyframe count | per keyframe: i32 id, u64 frame index, f64 timestamp,
//   f64[16] T_world_kf, i32 parent, f64[16] T_parent_this, depth (CV_32FC1 m), grey (CV_8UC1),
//   keypoints (f32 x y size angle response, i32 octave class_id), descriptors (CV_8U),
//   points (f64 x y z), fern code (u16s) | u64 edge count | per edge: i32 from to, f64[16]
//   T_from_to, f64[36] information, u8 is_loop
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "semap/core/pose.hpp"
#include "tracking/ferns.hpp"
#include "tracking/pose_graph.hpp"
#include "tracking/registration.hpp"

namespace semap {

struct Keyframe {
  int id = 0;
  size_t frame_index = 0;
  double timestamp = 0.0;
  cv::Mat depth;           ///< repaired depth, metres (pyramids are rebuilt from it on demand)
  cv::Mat gray;            ///< grey image (CV_8UC1) for the photometric ICP term
  FrameFeatures features;
  FernCode code;
  int parent = -1;         ///< keyframe it was tracked from
  Pose T_parent_this = Pose::Identity();
};

struct TrackerState {
  std::vector<std::shared_ptr<const Keyframe>> keyframes;  ///< ids 0..n-1 in order
  std::vector<Pose> T_world_keyframe;                      ///< indexed by id
  std::vector<PoseGraphEdge> edges;
};

inline constexpr const char* kTrackingSection = "tracking";

std::string encode_tracker_state(const TrackerState& state);
/// Throws semap::Error naming `path` for a corrupt or inconsistent section.
TrackerState decode_tracker_state(std::string_view bytes, const std::filesystem::path& path);

/// Map merging (issue 19): `b`'s keyframes and edges after `a`'s, in a's world frame. b's ids
/// (and parents, edge ends) are shifted by a's keyframe count and its poses become
/// T_a_b * T_b_keyframe; `links` join the two graphs (from: a's keyframe id, to: b's id before
/// the shift) as loop edges.
TrackerState append_tracker_state(TrackerState a, const TrackerState& b, const Pose& T_a_b,
                                  const std::vector<PoseGraphEdge>& links);

}  // namespace semap
