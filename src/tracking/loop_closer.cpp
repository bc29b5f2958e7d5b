#include "tracking/loop_closer.hpp"

#include <algorithm>
#include <functional>

#include "tracking/parallel.hpp"

namespace semap {

LoopCloser::LoopCloser(const TrackingConfig& config, const Odometry& odometry, const KeyframeDatabase& keyframes)
    : cfg_(config), odometry_(odometry), keyframes_(keyframes) {
  if (cfg_.background_loop_closure) worker_ = std::thread([this] { worker_loop(); });
}

LoopCloser::~LoopCloser() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

Pose LoopCloser::add_keyframe(int id, int parent, const Pose& T_parent_this, const Matrix6d& information) {
  std::lock_guard<std::mutex> lock(mutex_);
  Vertex v;
  v.parent = parent;
  v.T_parent_this = T_parent_this;
  v.T_world = parent >= 0 ? vertices_.at(parent).T_world * T_parent_this : Pose::Identity();
  vertices_[id] = v;
  if (parent >= 0) {
    PoseGraphEdge edge;
    edge.from = parent;
    edge.to = id;
    edge.T_from_to = T_parent_this;
    edge.information = information;
    graph_.add_edge(edge);
  }
  return v.T_world;
}

void LoopCloser::resume(const std::vector<std::shared_ptr<const Keyframe>>& keyframes,
                        const std::vector<Pose>& T_world_keyframe, const std::vector<PoseGraphEdge>& edges) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (size_t i = 0; i < keyframes.size(); ++i)
    vertices_[int(i)] = {T_world_keyframe[i], keyframes[i]->parent, keyframes[i]->T_parent_this};
  for (const PoseGraphEdge& e : edges) graph_.add_edge(e);
  fixed_below_ = int(keyframes.size());  // the saved map was fused with these poses
}

void LoopCloser::add_edge(const PoseGraphEdge& edge) {
  std::lock_guard<std::mutex> lock(mutex_);
  graph_.add_edge(edge);
}

Pose LoopCloser::pose(int id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return vertices_.at(id).T_world;
}

std::vector<Pose> LoopCloser::poses(std::initializer_list<int> ids) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Pose> out;
  for (const int id : ids) out.push_back(vertices_.at(id).T_world);
  return out;
}

std::map<int, Pose> LoopCloser::all_poses() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::map<int, Pose> out;
  for (const auto& [id, v] : vertices_) out[id] = v.T_world;
  return out;
}

std::vector<PoseGraphEdge> LoopCloser::edges() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return graph_.edges();
}

LoopClosureStats LoopCloser::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void LoopCloser::submit(int id) {
  if (!cfg_.pose_graph) return;
  if (!cfg_.background_loop_closure) return process_keyframe(id);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(id);
  }
  cv_.notify_all();
}

void LoopCloser::wait_idle() {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [&] { return queue_.empty() && !busy_; });
}

void LoopCloser::worker_loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    if (queue_.empty()) {
      if (stop_) return;
      continue;
    }
    const int id = queue_.front();
    queue_.pop_front();
    busy_ = true;
    lock.unlock();
    process_keyframe(id);
    lock.lock();
    busy_ = false;
    cv_.notify_all();
  }
}

/// A new keyframe's graph edges beyond its parent (A4): local edges to the keyframes it still
/// shares a view with, loop edges to old ones the ferns propose; optimises when any was added.
void LoopCloser::process_keyframe(int id) {
  const tracking_detail::SerialScope serial(!cfg_.parallel);
  const std::shared_ptr<const Keyframe> kf = keyframes_.get(id);
  // Registered as the source: the completed pyramid made with the keyframe when still cached,
  // else built only when a registration needs it (most keyframes have no loop candidate).
  auto cached = keyframes_.recent_target(id);
  const std::function<const std::vector<DepthLevel>&()> source = [&]() -> const std::vector<DepthLevel>& {
    if (!cached) cached = std::make_shared<const std::vector<DepthLevel>>(odometry_.pyramid(kf->depth, kf->gray, true));
    return *cached;
  };
  const bool local = add_local_edges(*kf, source);
  const bool loop = add_loop_edges(*kf, source);
  if (local || loop) optimise();
}

/// Local edges (issue 16): the parent chain alone drifts at every keyframe switch (fast
/// rotation switches keyframes several times a second). The keyframe is registered against
/// the nearest of the last few keyframes by pose (not its parent) from their current relative
/// pose, and each registration that converges there ties the two views directly.
bool LoopCloser::add_local_edges(const Keyframe& kf, const std::function<const std::vector<DepthLevel>&()>& kf_pyramid) {
  if (cfg_.local_edge_keyframes <= 0) return false;
  struct Target {
    double score;
    int id;
    Pose T_other_kf;  ///< current estimate: the ICP start
    std::shared_ptr<const std::vector<DepthLevel>> pyramid;
  };
  std::vector<Target> targets;
  const auto recent = keyframes_.recent_targets();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const Pose T_world_kf = vertices_.at(kf.id).T_world;
    for (const auto& [other, pyramid] : recent) {
      if (other >= kf.id || other == kf.parent) continue;
      const Pose T_other_kf = vertices_.at(other).T_world.inverse() * T_world_kf;
      const double score = keyframe_spacings(T_other_kf, cfg_);
      if (score <= cfg_.local_edge_max_score) targets.push_back({score, other, T_other_kf, pyramid});
    }
  }
  std::sort(targets.begin(), targets.end(), [](const Target& a, const Target& b) { return a.score < b.score; });
  if (int(targets.size()) > cfg_.local_edge_keyframes) targets.resize(size_t(cfg_.local_edge_keyframes));
  bool added = false;
  for (const auto& [score, other, guess, target] : targets) {
    const IcpResult icp = odometry_.refine(kf_pyramid(), *target, guess);
    // Verified as a loop is, and it must stay where the odometry put it (a local edge corrects
    // drift of a few keyframes, not a wrong basin).
    if (!odometry_.icp_acceptable(icp, cfg_.loop_max_icp_rmse, cfg_.loop_min_overlap) ||
        pose_distance(guess, icp.T_target_source) > cfg_.ransac.icp_agreement)
      continue;
    PoseGraphEdge edge;
    edge.from = other;
    edge.to = kf.id;
    edge.T_from_to = icp.T_target_source;
    edge.information = odometry_.information(icp);
    std::lock_guard<std::mutex> lock(mutex_);
    graph_.add_edge(edge);
    ++stats_.local_edges;
    added = true;
  }
  return added;
}

/// Looks for a loop from keyframe `kf` to older keyframes through the ferns (A3) and verifies
/// it geometrically (A2); true when a loop edge was added.
bool LoopCloser::add_loop_edges(const Keyframe& kf, const std::function<const std::vector<DepthLevel>&()>& kf_pyramid) {
  bool added = false;
  for (const auto& other : keyframes_.loop_candidates(kf)) {
    const auto other_pyramid = odometry_.pyramid(other->depth, other->gray);
    const OdometryResult reg = odometry_.register_to(kf.features, kf_pyramid(), other->features, other_pyramid, nullptr,
                                                     uint32_t(cfg_.seed) + uint32_t(kf.id) * 7919u);
    // The dense depth residual too (issue 42): a wrong loop edge pulls the whole graph.
    if (!reg.ok || !reg.check.dense_ok || reg.icp.rmse > cfg_.loop_max_icp_rmse || reg.icp.overlap < cfg_.loop_min_overlap)
      continue;
    std::lock_guard<std::mutex> lock(mutex_);
    const Pose current = vertices_.at(other->id).T_world.inverse() * vertices_.at(kf.id).T_world;
    if ((current.translation() - reg.T_kf_frame.translation()).norm() > cfg_.loop_max_pose_disagreement) continue;
    PoseGraphEdge edge;
    edge.from = other->id;
    edge.to = kf.id;
    edge.T_from_to = reg.T_kf_frame;
    edge.information = odometry_.information(reg.icp);
    edge.is_loop = true;
    graph_.add_edge(edge);
    ++stats_.loop_edges;
    added = true;
  }
  return added;
}

void LoopCloser::optimise() {
  PoseGraph snapshot;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [id, v] : vertices_) snapshot.add_vertex(id, v.T_world);
    for (const auto& e : graph_.edges()) snapshot.add_edge(e);
    snapshot.set_fixed_below(fixed_below_);
  }
  if (!snapshot.optimize(cfg_.pose_graph_iterations, cfg_.pose_graph_loop_huber)) return;
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& [id, pose] : snapshot.vertices()) vertices_[id].T_world = pose;
  for (auto& [id, v] : vertices_)  // in id order: a parent is corrected before its children
    if (!snapshot.has_vertex(id) && v.parent >= 0) v.T_world = vertices_.at(v.parent).T_world * v.T_parent_this;
  ++stats_.optimisations;
}

}  // namespace semap
