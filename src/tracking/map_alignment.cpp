#include "tracking/map_alignment.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace semap {
namespace {

struct Candidate {
  int other_id = 0;
  KeyframeMatch match;
  Pose T_this_other = Pose::Identity();
};

bool agree(const Pose& a, const Pose& b, const TrackingConfig& cfg) {
  const Pose d = a.inverse() * b;
  return d.translation().norm() <= cfg.merge_agreement_m && rotation_angle(d) * 180.0 / M_PI <= cfg.merge_agreement_deg;
}

/// The candidates that agree with the candidate most others agree with (ties: more inliers).
std::vector<const Candidate*> largest_agreeing_set(const std::vector<Candidate>& candidates, const TrackingConfig& cfg) {
  std::vector<const Candidate*> best;
  int best_inliers = -1;
  for (const Candidate& centre : candidates) {
    std::vector<const Candidate*> set;
    for (const Candidate& c : candidates)
      if (agree(centre.T_this_other, c.T_this_other, cfg)) set.push_back(&c);
    if (set.size() > best.size() || (set.size() == best.size() && centre.match.inliers > best_inliers)) {
      best = std::move(set);
      best_inliers = centre.match.inliers;
    }
  }
  return best;
}

/// Mean of nearby rigid transforms: translations averaged, rotations by the normalised sum of
/// sign-aligned quaternions (exact enough for transforms a few degrees apart).
Pose mean_pose(const std::vector<const Candidate*>& set) {
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Vector4d q_sum = Eigen::Vector4d::Zero();
  const Eigen::Quaterniond q0(set.front()->T_this_other.rotation());
  for (const Candidate* c : set) {
    t += c->T_this_other.translation();
    Eigen::Quaterniond q(c->T_this_other.rotation());
    if (q.dot(q0) < 0) q.coeffs() = -q.coeffs();
    q_sum += q.coeffs();
  }
  Eigen::Quaterniond q;
  q.coeffs() = q_sum.normalized();
  return pose_from_tq(t / double(set.size()), q);
}

}  // namespace

MapAlignment align_maps(const Tracker& tracker, const TrackerState& other) {
  const TrackingConfig& cfg = tracker.config();
  MapAlignment out;
  out.keyframes_tried = other.keyframes.size();
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < other.keyframes.size(); ++i) {
    const auto match = tracker.match_keyframe(*other.keyframes[i]);
    if (!match) continue;
    // T_this_other = T_this_kf_other * T_other_kf^-1: where the other map's world lies here.
    candidates.push_back({int(i), *match, orthonormalized(match->T_world_other * other.T_world_keyframe[i].inverse())});
  }
  out.keyframes_verified = candidates.size();
  if (candidates.empty()) {
    out.reason = "none of its " + std::to_string(other.keyframes.size()) + " keyframes relocalised";
    return out;
  }
  const std::vector<const Candidate*> set = largest_agreeing_set(candidates, cfg);
  out.keyframes_agreeing = set.size();
  const size_t needed = std::min<size_t>(size_t(cfg.merge_min_agreeing), other.keyframes.size());
  if (set.size() < needed) {
    out.reason = std::to_string(candidates.size()) + " of its " + std::to_string(other.keyframes.size()) +
                 " keyframes relocalised but at most " + std::to_string(set.size()) + " agree on one alignment (" +
                 std::to_string(needed) + " needed: tracking.merge_min_agreeing)";
    return out;
  }
  out.aligned = true;
  out.T_this_other = mean_pose(set);
  for (const Candidate* c : set) {
    PoseGraphEdge edge;
    edge.from = c->match.keyframe_id;
    edge.to = c->other_id;
    edge.T_from_to = c->match.T_keyframe_other;
    edge.information = c->match.information;
    edge.is_loop = true;
    out.links.push_back(edge);
  }
  return out;
}

}  // namespace semap
