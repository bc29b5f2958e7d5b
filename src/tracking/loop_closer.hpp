#pragma once
// Loop closure and the keyframe pose graph (METHODS.md A3 + A4): the keyframes' world poses,
// the graph's edges (odometry, re-use, local and loop edges), the worker that looks for loops
// and local edges of each new keyframe, and the Ceres optimisation.
#include <condition_variable>
#include <deque>
#include <functional>
#include <initializer_list>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include "tracking/keyframe_database.hpp"
#include "tracking/odometry.hpp"
#include "tracking/pose_graph.hpp"

namespace semap {

struct LoopClosureStats {
  size_t loop_edges = 0, local_edges = 0, optimisations = 0;
};

/// Thread safety: every public method may be called from any thread (one internal mutex guards
/// the poses, edges, queue and counters; registrations and the optimisation run outside it on a
/// snapshot). With background_loop_closure the keyframes submitted are processed on the
/// worker thread this object owns (joined by the destructor), else inline in submit().
class LoopCloser {
 public:
  /// `odometry` and `keyframes` must outlive the loop closer.
  LoopCloser(const TrackingConfig& config, const Odometry& odometry, const KeyframeDatabase& keyframes);
  ~LoopCloser();
  LoopCloser(const LoopCloser&) = delete;
  LoopCloser& operator=(const LoopCloser&) = delete;

  /// Adds keyframe `id`'s vertex at T_world_parent * T_parent_this (identity without parent)
  /// and, with a parent, its odometry edge; returns the pose. Call before the keyframe enters
  /// the KeyframeDatabase, so every keyframe found there has a pose.
  Pose add_keyframe(int id, int parent, const Pose& T_parent_this, const Matrix6d& information);
  /// Continues a saved map (issue 19): its keyframes' poses and edges; vertices below
  /// `fixed_below` stay fixed in every optimisation. Before the first add_keyframe().
  void resume(const std::vector<std::shared_ptr<const Keyframe>>& keyframes, const std::vector<Pose>& T_world_keyframe,
              const std::vector<PoseGraphEdge>& edges);
  void add_edge(const PoseGraphEdge& edge);
  /// T_world_keyframe, latest estimate. Throws std::out_of_range for an unknown id.
  Pose pose(int id) const;
  /// The poses of `ids`, read together (one consistent graph state).
  std::vector<Pose> poses(std::initializer_list<int> ids) const;
  /// Every keyframe's pose by id.
  std::map<int, Pose> all_poses() const;
  std::vector<PoseGraphEdge> edges() const;
  LoopClosureStats stats() const;

  /// Queues keyframe `id` (in the KeyframeDatabase) for local and loop edges (no-op without
  /// pose_graph); inline without background_loop_closure.
  void submit(int id);
  /// Waits until the queue is empty and the worker idle.
  void wait_idle();
  /// Optimises a snapshot of the graph without holding the lock, then applies the result;
  /// keyframes added meanwhile follow their parent's correction.
  void optimise();

 private:
  struct Vertex {
    Pose T_world = Pose::Identity();
    int parent = -1;
    Pose T_parent_this = Pose::Identity();
  };
  void worker_loop();
  void process_keyframe(int id);
  bool add_local_edges(const Keyframe& kf, const std::function<const std::vector<DepthLevel>&()>& kf_pyramid);
  bool add_loop_edges(const Keyframe& kf, const std::function<const std::vector<DepthLevel>&()>& kf_pyramid);

  TrackingConfig cfg_;
  const Odometry& odometry_;
  const KeyframeDatabase& keyframes_;
  mutable std::mutex mutex_;
  std::map<int, Vertex> vertices_;  ///< by keyframe id
  PoseGraph graph_;                 ///< edges only; vertices are snapshot from vertices_
  int fixed_below_ = 0;
  LoopClosureStats stats_;
  std::condition_variable cv_;
  std::deque<int> queue_;
  bool stop_ = false, busy_ = false;
  std::thread worker_;  ///< last member: started after the rest is built
};

}  // namespace semap
