#pragma once
// Aligning two saved maps of the same place (map merging, issue 19): the other map's keyframes
// are relocalised into this tracker's keyframes (METHODS.md A3 + A2, as a lost frame is), each
// verified registration implies one rigid transform between the two world frames, and the
// transforms must agree: one registration can be wrong (a repeated texture, a look-alike
// room), several independent views agreeing on one alignment are not by chance.
#include <optional>
#include <string>
#include <vector>

#include "semap/core/pose.hpp"
#include "tracking/pose_graph.hpp"
#include "tracking/tracker.hpp"
#include "tracking/tracker_state.hpp"

namespace semap {

struct MapAlignment {
  bool aligned = false;
  std::string reason;                  ///< why not, when not aligned
  Pose T_this_other = Pose::Identity();  ///< the other map's world in this tracker's world
  size_t keyframes_tried = 0;          ///< the other map's keyframes
  size_t keyframes_verified = 0;       ///< relocalised (a verified registration)
  size_t keyframes_agreeing = 0;       ///< whose alignment agrees with the chosen one
  /// Loop edges joining the graphs: from this tracker's keyframe to the other's keyframe (its
  /// id in the other map), for the agreeing registrations.
  std::vector<PoseGraphEdge> links;
};

/// Relocalises every keyframe of `other` into `tracker` (Tracker::match_keyframe) and picks
/// the alignment most of them agree on (within tracking.merge_agreement_m / _deg; at least
/// merge_min_agreeing of them, or the one keyframe of a one-keyframe map). T_this_other is the
/// mean of the agreeing ones. Uses the tracker's threads' config only; changes nothing.
MapAlignment align_maps(const Tracker& tracker, const TrackerState& other);

}  // namespace semap
