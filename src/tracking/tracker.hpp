#pragma once
// Camera tracking (METHODS.md A1-A4): depth repair, then three parts (issue 42), each with its
// own lock and its thread safety stated per method:
//   Odometry (odometry.hpp)               frame-to-keyframe registration, ORB + voting RANSAC +
//                                         point-to-plane ICP, returning an OdometryResult;
//   KeyframeDatabase (keyframe_database.hpp)  keyframes, random ferns, relocalisation, map-merge matching;
//   LoopCloser (loop_closer.hpp)          the keyframe pose graph (Ceres) and the loop-closure worker.
// Tracker::track runs the per-frame steps over them and keeps the reference and motion prior.
//
// Poses: T_world_camera, world = first frame's camera. Every frame is stored relative to its
// reference keyframe, so corrections of keyframe poses (pose graph) move the frames with them.
#include <memory>
#include <optional>
#include <opencv2/core.hpp>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"
#include "semap/core/pose.hpp"
#include "semap/tracking/tracking_config.hpp"
#include "tracking/model_view.hpp"
#include "tracking/registration.hpp"
#include "tracking/registration_check.hpp"

namespace semap {

enum class TrackingStatus { ok, lost, relocalised };
const char* to_string(TrackingStatus status);

/// Milliseconds spent in each part of Tracker::track (per-frame path only).
struct TrackTimings {
  double repair_ms = 0, features_ms = 0, ransac_ms = 0, icp_ms = 0, keyframe_ms = 0, total_ms = 0;
};

struct TrackResult {
  size_t frame_index = 0;
  double timestamp = 0.0;
  Pose T_world_camera = Pose::Identity();  ///< current best estimate (uses the latest keyframe poses)
  bool is_keyframe = false;                ///< this frame became a new keyframe
  TrackingStatus status = TrackingStatus::ok;
  int reference_keyframe = -1;             ///< keyframe id the frame was registered against (-1: held, see resume())
  int feature_matches = 0;                 ///< ORB matches to the reference keyframe
  int ransac_inliers = 0;                  ///< voting-RANSAC inliers (0 when RANSAC failed)
  bool used_motion_prior = false;          ///< ICP started from the motion prior (too few inliers)
  int icp_matched = 0;
  double icp_rmse = 0.0;                   ///< metres
  double icp_overlap = 0.0;                ///< matched fraction of the frame's points
  RegistrationCheck check;                 ///< verification of the registration to the reference (issue 42)
  cv::Mat depth;                           ///< depth used for tracking (repaired when enabled), CV_32FC1 metres
  TrackTimings timings;
  /// The pose passed its checks (tracked or relocalised); a frame without a verified pose must
  /// not be integrated (the Mapper skips it).
  bool pose_verified() const { return status != TrackingStatus::lost; }
};

struct KeyframeInfo {
  int id = 0;
  size_t frame_index = 0;
  double timestamp = 0.0;
  Pose T_world_camera = Pose::Identity();  ///< latest (optimised) pose
};

struct TrackerStats {
  size_t frames = 0, keyframes = 0, lost_frames = 0, relocalisations = 0;
  size_t loop_edges = 0, local_edges = 0, keyframe_reuses = 0, optimisations = 0;
  size_t resumed_keyframes = 0;  ///< keyframes of the map this tracker continues (resume())
  size_t held_frames = 0;        ///< frames of a resumed map before the first relocalisation
  /// Issue 42: frames whose registration to the reference was verified, and how often each
  /// check failed on it (registration_check.hpp).
  size_t verified_registrations = 0, dense_residual_failed = 0, spread_failed = 0, ambiguous_matches = 0,
         under_constrained = 0;
};

struct TrackerState;  // tracking/tracker_state.hpp
struct Keyframe;      // tracking/tracker_state.hpp

/// A keyframe of another map registered against this tracker's keyframes (map merging, issue 19).
struct KeyframeMatch {
  int keyframe_id = -1;                    ///< this tracker's keyframe it verified against
  Pose T_world_other = Pose::Identity();   ///< the other keyframe's camera in this tracker's world
  Pose T_keyframe_other = Pose::Identity();  ///< the registration itself
  Matrix6d information = Matrix6d::Identity();  ///< of T_keyframe_other (pose-graph edge)
  int inliers = 0;                         ///< voting-RANSAC inliers
  double overlap = 0.0, rmse_m = 0.0;      ///< ICP overlap fraction and residual
};

/// Thread safety: track(), resume() and finish() are called by one thread (the tracking
/// thread); trajectory(), keyframes(), stats(), state(), match_keyframe() and config() may be
/// called from any thread at the same time (each part guards its own data).
class Tracker {
 public:
  /// Validates the config (throws semap::Error). Colour must be registered to depth (an image of
  /// another size is resized to the depth size). Frames are pinhole images: a camera with lens
  /// distortion is an error (dataset readers and the Mapper undistort first).
  Tracker(const TrackingConfig& config, const CameraModel& camera);
  ~Tracker();
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;

  /// The fused model the keyframe targets are taken from (tracking.model_keyframes; METHODS.md
  /// A2 frame-to-model); nullptr: keyframes keep their own depth. Call before the first frame,
  /// from the tracking thread.
  void set_model_view(std::shared_ptr<const ModelView> model);
  /// Tracks one frame (frames in sequence order). Throws semap::Error for empty/mistyped images.
  TrackResult track(const Frame& frame);
  /// Waits for pending loop closure, runs the final pose-graph optimisation and returns the
  /// pose of every tracked frame (optimised keyframe pose * relative pose to it), as trajectory().
  Trajectory finish();
  /// Every tracked frame with the current keyframe poses (no waiting, no optimisation). Frames
  /// held before a resumed map relocalised have no pose and are left out.
  Trajectory trajectory() const;
  /// Keyframes with their latest poses; after finish() these are the optimised poses the map
  /// should be re-integrated with.
  std::vector<KeyframeInfo> keyframes() const;
  TrackerStats stats() const;
  /// The keyframe database and pose graph (map.semap's tracking section, issue 19).
  TrackerState state() const;
  /// Continues a saved map (issue 19): its keyframes become this tracker's first keyframes and
  /// stay fixed in the pose graph (the saved map was fused with their poses). Each frame is
  /// relocalised against them (A3) and held, with status lost and no pose in trajectory(),
  /// until one verifies; tracking, keyframes and loop edges then continue in the map's world
  /// frame. Call before the first frame; throws semap::Error otherwise.
  void resume(const TrackerState& state);
  /// Relocalises `other` (a keyframe of another saved map: its features, depth, grey image and
  /// fern code) against this tracker's keyframes as a lost frame is (METHODS A3: the most
  /// similar keyframes by ferns, wide-baseline A2 registration, the relocalisation overlap).
  /// Changes nothing. Thread-safe against track() on another thread.
  std::optional<KeyframeMatch> match_keyframe(const Keyframe& other) const;
  const TrackingConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace semap
