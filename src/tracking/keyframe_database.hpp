#pragma once
// The keyframe database (METHODS.md A3): keyframes with their features, depth and fern codes,
// fern look-ups for relocalisation and loop candidates, and the registration of a lost frame
// or of another map's keyframe against them (relocalisation, map merging, issue 19).
// Keyframe poses live in the pose graph (LoopCloser), not here.
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "tracking/ferns.hpp"
#include "tracking/odometry.hpp"
#include "tracking/tracker_state.hpp"

namespace semap {

/// A frame registered against a stored keyframe (relocalisation or map merging).
struct KeyframeRegistration {
  std::shared_ptr<const Keyframe> keyframe;
  OdometryResult registration;
  std::vector<DepthLevel> keyframe_pyramid;  ///< the completed ICP target pyramid used
};

/// Thread safety: every method may be called from any thread (one internal mutex guards the
/// keyframes, the fern table and the target cache; registrations run outside it). add() is
/// called by one thread only (the tracking thread), which makes ids increase in order.
class KeyframeDatabase {
 public:
  /// `odometry` must outlive the database.
  KeyframeDatabase(const TrackingConfig& config, const Odometry& odometry);

  /// Adds a keyframe; its id must be size() (ids 0..n-1 in order). Tracking thread only.
  void add(std::shared_ptr<const Keyframe> keyframe);
  std::shared_ptr<const Keyframe> get(int id) const;
  std::vector<std::shared_ptr<const Keyframe>> all() const;
  size_t size() const;

  /// Fern code of an RGB-D frame (A3). No lock: the fern tests never change.
  FernCode encode(const cv::Mat& rgb, const cv::Mat& depth) const { return ferns_.encode(rgb, depth); }
  /// Best fern similarity of `code` to any keyframe (0 when empty).
  double max_similarity(const FernCode& code) const;
  /// The `count` keyframes most similar to `code` by ferns, best first (stable for ties).
  std::vector<std::shared_ptr<const Keyframe>> most_similar(const FernCode& code, int count) const;
  /// Loop candidates of keyframe `kf` (A3): at least loop_min_keyframe_gap keyframes older,
  /// similarity >= loop_min_similarity, the loop_candidates best first.
  std::vector<std::shared_ptr<const Keyframe>> loop_candidates(const Keyframe& kf) const;

  /// Registers a lost frame (A3): against the `reference` keyframe (its pyramid given, the
  /// camera is usually still near where it was lost), the most similar keyframes by ferns and
  /// the most recent ones, with the wide-baseline effort; the first feature-supported
  /// registration with relocalisation_min_overlap wins.
  std::optional<KeyframeRegistration> relocalise(const FrameFeatures& features, const std::vector<DepthLevel>& frame_pyramid,
                                                 const FernCode& code, int reference,
                                                 const std::vector<DepthLevel>& reference_pyramid) const;
  /// Registers a keyframe of another map as a lost frame is (map merging): against the most
  /// similar keyframes by ferns. Changes nothing.
  std::optional<KeyframeRegistration> match(const Keyframe& other) const;

  /// Keeps `id`'s completed target pyramid as one of the local_edge_keyframes + 1 keyframes
  /// referenced last (local edges, A4): a fresh pyramid costs more than a registration.
  void remember_target(int id, const std::vector<DepthLevel>& pyramid);
  std::shared_ptr<const std::vector<DepthLevel>> recent_target(int id) const;
  /// The cached target pyramids by keyframe id.
  std::map<int, std::shared_ptr<const std::vector<DepthLevel>>> recent_targets() const;

 private:
  bool accepted_as_relocalisation(const OdometryResult& reg) const;
  std::vector<std::shared_ptr<const Keyframe>> most_similar_locked(const FernCode& code, int count) const;

  TrackingConfig cfg_;
  const Odometry& odometry_;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<const Keyframe>> keyframes_;  ///< by id
  FernDatabase ferns_;
  struct RecentTarget {
    uint64_t last_use = 0;
    std::shared_ptr<const std::vector<DepthLevel>> pyramid;
  };
  std::map<int, RecentTarget> recent_targets_;
  uint64_t target_uses_ = 0;
};

}  // namespace semap
