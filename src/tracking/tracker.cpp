#include "tracking/tracker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <cstdio>
#include <cstdlib>

#include "semap/core/error.hpp"
#include "tracking/depth_repair.hpp"
#include "tracking/ferns.hpp"
#include "tracking/parallel.hpp"
#include "tracking/pose_graph.hpp"
#include "tracking/registration.hpp"
#include "tracking/tracker_state.hpp"

namespace semap {

const char* to_string(TrackingStatus status) {
  switch (status) {
    case TrackingStatus::ok: return "ok";
    case TrackingStatus::lost: return "lost";
    case TrackingStatus::relocalised: return "relocalised";
  }
  return "?";
}

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
double deg(double rad) { return rad * 180.0 / M_PI; }

struct FrameRecord {
  size_t frame_index = 0;
  double timestamp = 0.0;
  int reference = 0;
  Pose T_ref_frame = Pose::Identity();
};

/// Outcome of registering a frame against a keyframe (A2).
struct Registration {
  bool ok = false;                 ///< ICP converged with acceptable residual and overlap
  bool feature_supported = false;  ///< trusted RANSAC estimate that the ICP result agrees with
  bool accepted = false;           ///< ok, and feature-supported or plausible against the prior
  Pose T_kf_frame = Pose::Identity();
  int matches = 0, inliers = 0;
  bool used_prior = false;
  IcpResult icp;
  double ransac_ms = 0, icp_ms = 0;
};

/// How hard a registration tries: the per-frame path first, the wide-baseline one only when
/// that failed (issue 16: consecutive-frame speed stays as it was).
enum class Effort { normal, wide };

/// Translation + rotation (radians x 0.5 m lever) distance of two poses, metres.
double pose_distance(const Pose& a, const Pose& b) {
  const Pose d = a.inverse() * b;
  return d.translation().norm() + 0.5 * rotation_angle(d);
}
}  // namespace

struct Tracker::Impl {
  TrackingConfig cfg;
  CameraModel camera;
  PinholeIntrinsics intr;
  cv::Ptr<cv::ORB> orb;
  IcpParams icp_params, wide_icp_params;

  // Shared with the loop-closure worker (guarded by mutex).
  mutable std::mutex mutex;
  std::vector<std::shared_ptr<const Keyframe>> keyframes;
  std::map<int, Pose> kf_pose;  ///< T_world_kf, latest estimate
  PoseGraph graph;
  FernDatabase ferns;
  TrackerStats stats;
  uint64_t pose_version = 0;  ///< bumped whenever keyframe poses are corrected
  /// Completed ICP target pyramids of the local_edge_keyframes + 1 keyframes referenced last
  /// (made, re-used or relocalised into), kept for local edges: a fresh pyramid costs more than
  /// the registration itself (first-touch memory).
  struct RecentTarget {
    uint64_t last_use = 0;
    std::shared_ptr<const std::vector<DepthLevel>> pyramid;
  };
  std::map<int, RecentTarget> recent_targets;
  uint64_t target_uses = 0;

  // Worker.
  std::thread worker;
  std::condition_variable cv;
  std::deque<int> queue;
  bool stop = false;
  bool busy = false;

  // Per-frame state (main thread only).
  std::vector<FrameRecord> frames;
  int reference = -1;
  std::vector<DepthLevel> ref_pyramid;
  Pose T_ref_last = Pose::Identity();
  Pose velocity = Pose::Identity();  ///< T_{k-2}^{-1} T_{k-1}
  bool velocity_valid = false;
  uint64_t seen_version = 0;
  bool lost = false;
  int resumed_keyframes = 0;  ///< keyframes 0..n-1 came from a saved map (resume): fixed, relocalised into

  Impl(const TrackingConfig& c, const CameraModel& cam)
      : cfg(c), camera(cam), intr(cam.depth), ferns(make_fern_params(c)) {
    cfg.validate();
    orb = cv::ORB::create(cfg.orb_features, float(cfg.orb_scale_factor), cfg.orb_levels, 19, 0, 2,
                          cv::ORB::HARRIS_SCORE, 31, cfg.orb_fast_threshold);
    icp_params = cfg.icp;
    // Wide-baseline ICP (issue 16): twice the coarse iterations, the basin is at the coarse levels.
    wide_icp_params = cfg.icp;
    wide_icp_params.iterations_coarse = 2 * cfg.icp.iterations_coarse;
    wide_icp_params.iterations_mid = 2 * cfg.icp.iterations_mid;
    if (cfg.background_loop_closure) worker = std::thread([this] { worker_loop(); });
  }

  ~Impl() { stop_worker(); }

  static FernParams make_fern_params(const TrackingConfig& c) {
    FernParams p;
    p.fern_count = c.fern_count;
    p.fern_tests = c.fern_tests;
    p.width = c.fern_width;
    p.height = c.fern_height;
    p.min_depth = c.min_depth;
    p.max_depth = c.max_depth;
    p.seed = uint32_t(c.seed);
    return p;
  }

  void stop_worker() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      stop = true;
    }
    cv.notify_all();
    if (worker.joinable()) worker.join();
  }


  /// Keyframe (ICP target) pyramid; `source_only` for a tracked frame (completed by
  /// make_keyframe if it becomes one; METHODS.md A2 step 4).
  std::vector<DepthLevel> pyramid(const cv::Mat& depth, const cv::Mat& gray, bool source_only = false) const {
    return build_depth_pyramid(depth, intr, cfg.icp.levels, cfg.min_depth, cfg.max_depth, true,
                               cfg.icp.photometric_weight > 0 ? gray : cv::Mat(), source_only);
  }

  bool icp_acceptable(const IcpResult& icp, double max_rmse, double min_overlap) const {
    return icp.converged && icp.rmse <= max_rmse && icp.overlap >= min_overlap;
  }

  /// An estimate without trusted feature support must stay near the motion prior (A2).
  bool plausible(const Pose& prior, const Pose& T_ref_frame) const {
    const Pose jump = prior.inverse() * T_ref_frame;
    return jump.translation().norm() <= cfg.loss_max_translation_jump &&
           deg(rotation_angle(jump)) <= cfg.loss_max_rotation_jump_deg;
  }

  /// Judges an ICP result from the registration's own evidence (issue 16): converged with
  /// acceptable residual and overlap; trusted when a well-supported RANSAC estimate agrees
  /// with it, else it must be plausible against the prior (without a prior: not accepted).
  void judge(Registration& reg, const RansacResult& ransac, bool trusted, const Pose* prior) const {
    reg.T_kf_frame = reg.icp.T_target_source;
    reg.ok = icp_acceptable(reg.icp, cfg.loss_max_icp_rmse, cfg.loss_min_overlap);
    reg.feature_supported = trusted && pose_distance(ransac.T, reg.T_kf_frame) <= cfg.ransac_icp_agreement;
    reg.accepted = reg.ok && (reg.feature_supported || (prior && plausible(*prior, reg.T_kf_frame)));
  }

  /// The wide-baseline ICP gate: grows with how far the start may be off (the prior's own step).
  IcpParams wide_params(double expected_error_m) const {
    IcpParams p = wide_icp_params;
    p.max_distance = std::clamp(cfg.wide_icp_gate_factor * expected_error_m, cfg.icp.max_distance,
                                std::max(cfg.icp.max_distance, cfg.wide_icp_max_distance));
    return p;
  }

  /// A2: features -> voting RANSAC -> ICP from RANSAC, else (or when that is not accepted)
  /// from the prior. `prior_step_m`: how far the prior may be off (its own step), for the gate.
  Registration register_to(const FrameFeatures& frame_features, const std::vector<DepthLevel>& frame_pyramid,
                           const FrameFeatures& kf_features, const std::vector<DepthLevel>& kf_pyramid,
                           const Pose* prior, uint32_t seed, Effort effort = Effort::normal,
                           double prior_step_m = 0.0) const {
    Registration reg;
    auto t0 = Clock::now();
    const auto pairs = match_features(frame_features, kf_features, cfg.match_ratio, cfg.match_max_hamming);
    reg.matches = int(pairs.size());
    std::vector<Eigen::Vector3d> src, dst;
    for (const auto& [q, t] : pairs) {
      src.push_back(frame_features.points[q]);
      dst.push_back(kf_features.points[t]);
    }
    RansacParams rp;
    rp.iterations = effort == Effort::wide ? cfg.wide_ransac_iterations : cfg.ransac_iterations;
    rp.inlier_distance = cfg.ransac_inlier_distance;
    rp.min_inliers = cfg.ransac_min_inliers;
    rp.seed = seed;
    const RansacResult ransac = ransac_rigid(src, dst, rp);
    reg.inliers = ransac.ok ? int(ransac.inliers.size()) : 0;
    const bool trusted = ransac.ok && reg.inliers >= cfg.ransac_trusted_inliers &&
                         reg.inliers >= cfg.ransac_trusted_ratio * reg.matches;
    reg.ransac_ms = ms_since(t0);
    t0 = Clock::now();
    const IcpParams& params = effort == Effort::wide ? wide_icp_params : icp_params;
    if (ransac.ok) {
      reg.icp = icp_point_to_plane(frame_pyramid, kf_pyramid, ransac.T, params);
      judge(reg, ransac, trusted, prior);
    }
    // RANSAC on a few bad matches can mislead ICP; the prior is the second chance.
    if (!reg.accepted && prior) {
      Registration second = reg;
      second.icp = icp_point_to_plane(frame_pyramid, kf_pyramid, *prior,
                                      effort == Effort::wide ? wide_params(prior_step_m) : icp_params);
      judge(second, ransac, trusted, prior);
      second.used_prior = true;
      if (second.accepted || !ransac.ok) reg = second;
    }
    reg.icp_ms = ms_since(t0);
    return reg;
  }

  Matrix6d edge_information(const IcpResult& icp) const {
    return information_from_icp(icp.hessian, icp.T_target_source, icp.matched,
                                std::max(icp.rmse, cfg.information_min_sigma), cfg.information_effective_points);
  }

  Pose world_pose_locked(int kf) const { return kf_pose.at(kf); }

  // --- loop closure (A3 + A4), on the worker or inline ---
  void worker_loop() {
    std::unique_lock<std::mutex> lock(mutex);
    while (true) {
      cv.wait(lock, [&] { return stop || !queue.empty(); });
      if (queue.empty()) {
        if (stop) return;
        continue;
      }
      const int id = queue.front();
      queue.pop_front();
      busy = true;
      lock.unlock();
      process_keyframe(id);
      lock.lock();
      busy = false;
      cv.notify_all();
    }
  }

  void wait_idle() {
    std::unique_lock<std::mutex> lock(mutex);
    cv.wait(lock, [&] { return queue.empty() && !busy; });
  }

  void submit_keyframe(int id) {
    if (!cfg.pose_graph) return;
    if (cfg.background_loop_closure) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        queue.push_back(id);
      }
      cv.notify_all();
    } else {
      process_keyframe(id);
    }
  }

  using SourcePyramid = std::function<const std::vector<DepthLevel>&()>;

  /// Keeps `id`'s completed target pyramid as one of the most recently referenced keyframes.
  void remember_target(int id, const std::vector<DepthLevel>& target) {
    if (cfg.local_edge_keyframes <= 0) return;
    std::lock_guard<std::mutex> lock(mutex);
    recent_targets[id] = {++target_uses, std::make_shared<const std::vector<DepthLevel>>(target)};  // shares the pixels
    while (int(recent_targets.size()) > cfg.local_edge_keyframes + 1) {
      auto oldest = recent_targets.begin();
      for (auto it = recent_targets.begin(); it != recent_targets.end(); ++it)
        if (it->second.last_use < oldest->second.last_use) oldest = it;
      recent_targets.erase(oldest);
    }
  }

  std::shared_ptr<const std::vector<DepthLevel>> recent_target(int id) const {
    std::lock_guard<std::mutex> lock(mutex);
    const auto it = recent_targets.find(id);
    return it == recent_targets.end() ? nullptr : it->second.pyramid;
  }

  /// A new keyframe's graph edges beyond its parent (A4): local edges to the keyframes it still
  /// shares a view with, loop edges to old ones the ferns propose; optimises when any was added.
  void process_keyframe(int id) {
    const tracking_detail::SerialScope serial(!cfg.parallel);
    std::shared_ptr<const Keyframe> kf;
    {
      std::lock_guard<std::mutex> lock(mutex);
      kf = keyframes[id];
    }
    // Registered as the source: the completed pyramid made with the keyframe when still cached,
    // else built only when a registration needs it (most keyframes have no loop candidate).
    auto cached = recent_target(id);
    const SourcePyramid source = [&]() -> const std::vector<DepthLevel>& {
      if (!cached) cached = std::make_shared<const std::vector<DepthLevel>>(pyramid(kf->depth, kf->gray, true));
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
  bool add_local_edges(const Keyframe& kf, const SourcePyramid& kf_pyramid) {
    if (cfg.local_edge_keyframes <= 0) return false;
    struct Target {
      double score;
      int id;
      Pose T_other_kf;  ///< current estimate: the ICP start
      std::shared_ptr<const std::vector<DepthLevel>> pyramid;
    };
    std::vector<Target> targets;
    {
      std::lock_guard<std::mutex> lock(mutex);
      const Pose T_world_kf = kf_pose.at(kf.id);
      for (const auto& [other, entry] : recent_targets) {
        if (other >= kf.id || other == kf.parent) continue;
        const Pose T_other_kf = kf_pose.at(other).inverse() * T_world_kf;
        const double score = keyframe_score(T_other_kf);
        if (score <= cfg.local_edge_max_score) targets.push_back({score, other, T_other_kf, entry.pyramid});
      }
    }
    std::sort(targets.begin(), targets.end(), [](const Target& a, const Target& b) { return a.score < b.score; });
    if (int(targets.size()) > cfg.local_edge_keyframes) targets.resize(size_t(cfg.local_edge_keyframes));
    bool added = false;
    for (const auto& [score, other, guess, target] : targets) {
      const IcpResult icp = icp_point_to_plane(kf_pyramid(), *target, guess, icp_params);
      // Verified as a loop is, and it must stay where the odometry put it (a local edge corrects
      // drift of a few keyframes, not a wrong basin).
      if (!icp_acceptable(icp, cfg.loop_max_icp_rmse, cfg.loop_min_overlap) ||
          pose_distance(guess, icp.T_target_source) > cfg.ransac_icp_agreement)
        continue;
      PoseGraphEdge edge;
      edge.from = other;
      edge.to = kf.id;
      edge.T_from_to = icp.T_target_source;
      edge.information = edge_information(icp);
      std::lock_guard<std::mutex> lock(mutex);
      graph.add_edge(edge);
      ++stats.local_edges;
      added = true;
    }
    return added;
  }

  /// Pose distance in keyframe spacings: translation / keyframe_translation + rotation /
  /// keyframe_rotation_deg (1 = the motion that makes a new keyframe).
  double keyframe_score(const Pose& rel) const {
    return rel.translation().norm() / cfg.keyframe_translation + deg(rotation_angle(rel)) / cfg.keyframe_rotation_deg;
  }

  /// Looks for a loop from keyframe `kf` to older keyframes through the ferns (A3) and verifies
  /// it geometrically (A2); true when a loop edge was added.
  bool add_loop_edges(const Keyframe& kf, const SourcePyramid& kf_pyramid) {
    const int id = kf.id;
    std::vector<std::pair<double, std::shared_ptr<const Keyframe>>> candidates;
    {
      std::lock_guard<std::mutex> lock(mutex);
      const auto sims = ferns.similarities(kf.code);
      const auto& ids = ferns.ids();
      for (size_t i = 0; i < ids.size(); ++i) {
        const int other = ids[i];
        if (id - other < cfg.loop_min_keyframe_gap || sims[i] < cfg.loop_min_similarity) continue;
        candidates.emplace_back(sims[i], keyframes[other]);
      }
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    if (int(candidates.size()) > cfg.loop_candidates) candidates.resize(cfg.loop_candidates);
    bool added = false;
    for (const auto& [sim, other] : candidates) {
      const auto other_pyramid = pyramid(other->depth, other->gray);
      Registration reg = register_to(kf.features, kf_pyramid(), other->features, other_pyramid, nullptr,
                                     uint32_t(cfg.seed) + uint32_t(id) * 7919u);
      if (!reg.ok || reg.icp.rmse > cfg.loop_max_icp_rmse || reg.icp.overlap < cfg.loop_min_overlap) continue;
      std::lock_guard<std::mutex> lock(mutex);
      const Pose current = kf_pose.at(other->id).inverse() * kf_pose.at(id);
      if ((current.translation() - reg.T_kf_frame.translation()).norm() > cfg.loop_max_pose_disagreement) continue;
      PoseGraphEdge edge;
      edge.from = other->id;
      edge.to = id;
      edge.T_from_to = reg.T_kf_frame;
      edge.information = edge_information(reg.icp);
      edge.is_loop = true;
      graph.add_edge(edge);
      ++stats.loop_edges;
      added = true;
    }
    return added;
  }

  /// Optimises a snapshot of the graph without holding the lock, then applies the result;
  /// keyframes added meanwhile follow their parent's correction.
  void optimise() {
    PoseGraph snapshot;
    {
      std::lock_guard<std::mutex> lock(mutex);
      for (const auto& [id, pose] : kf_pose) snapshot.add_vertex(id, pose);
      for (const auto& e : graph.edges()) snapshot.add_edge(e);
    }
    snapshot.set_fixed_below(resumed_keyframes);  // the saved map was fused with these poses
    if (!snapshot.optimize(cfg.pose_graph_iterations, cfg.pose_graph_loop_huber)) return;
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& [id, pose] : snapshot.vertices()) kf_pose[id] = pose;
    for (const auto& kf : keyframes)
      if (!snapshot.has_vertex(kf->id) && kf->parent >= 0) kf_pose[kf->id] = kf_pose.at(kf->parent) * kf->T_parent_this;
    ++stats.optimisations;
    ++pose_version;
  }

  /// Frame-to-reference registration from the motion prior, then with the wide-baseline effort
  /// when that failed (issue 16: consecutive-frame speed stays as it was).
  Registration register_to_reference(const FrameFeatures& features, const std::vector<DepthLevel>& frame_pyramid,
                                     const Pose& prior, size_t frame_index, TrackResult& result) {
    std::shared_ptr<const Keyframe> ref_kf;
    {
      std::lock_guard<std::mutex> lock(mutex);
      ref_kf = keyframes[reference];
    }
    const uint32_t seed = uint32_t(cfg.seed) + uint32_t(frame_index);
    Registration reg = register_to(features, frame_pyramid, ref_kf->features, ref_pyramid, &prior, seed);
    result.timings.ransac_ms = reg.ransac_ms;
    result.timings.icp_ms = reg.icp_ms;
    if (reg.accepted) return reg;
    const double step = velocity_valid && !lost ? pose_distance(Pose::Identity(), velocity) : 0.0;
    Registration wide = register_to(features, frame_pyramid, ref_kf->features, ref_pyramid, &prior,
                                    seed * 2654435761u + 17u, Effort::wide, step);
    result.timings.ransac_ms += wide.ransac_ms;
    result.timings.icp_ms += wide.icp_ms;
    return wide.accepted ? wide : reg;
  }

  // --- per-frame path ---
  TrackResult track(const Frame& frame) {
    const auto t_start = Clock::now();
    const tracking_detail::SerialScope serial(!cfg.parallel);
    if (frame.depth.empty() || frame.depth.type() != CV_32FC1)
      throw Error(frame.depth_path.empty() ? "Tracker::track" : frame.depth_path, "depth must be CV_32FC1 metres");
    if (frame.rgb.empty() || frame.rgb.type() != CV_8UC3)
      throw Error(frame.rgb_path.empty() ? "Tracker::track" : frame.rgb_path, "rgb must be CV_8UC3");
    if (frame.depth.cols != intr.width || frame.depth.rows != intr.height)
      throw Error(frame.depth_path.empty() ? "Tracker::track" : frame.depth_path, "depth size differs from the camera model");
    TrackResult result;
    result.frame_index = frame.index;
    result.timestamp = frame.timestamp;

    cv::Mat rgb = frame.rgb;
    if (rgb.size() != frame.depth.size()) cv::resize(frame.rgb, rgb, frame.depth.size(), 0, 0, cv::INTER_AREA);
    cv::Mat gray;
    cv::cvtColor(rgb, gray, cv::COLOR_BGR2GRAY);

    auto t0 = Clock::now();
    cv::Mat depth = frame.depth;
    if (cfg.depth_repair) {
      DepthRepairParams rp{cfg.depth_repair_radius, cfg.depth_repair_gray_threshold, cfg.depth_repair_min_support};
      depth = repair_depth(frame.depth, gray, rp);
    }
    result.depth = depth;  // the frame's own pixel grid (the map integrates it with the colour)
    result.timings.repair_ms = ms_since(t0);

    t0 = Clock::now();
    FrameFeatures features = extract_features(*orb, gray, depth, intr, cfg.min_depth, cfg.max_depth);
    std::vector<DepthLevel> frame_pyramid = pyramid(depth, gray, /*source_only=*/true);
    result.timings.features_ms = ms_since(t0);

    if (reference < 0 && resumed_keyframes == 0) {  // first frame: world = its camera
      t0 = Clock::now();
      make_keyframe(frame, depth, gray, std::move(features), ferns.encode(rgb, depth), std::move(frame_pyramid), -1,
                    Pose::Identity(), IcpResult{});
      result.is_keyframe = true;
      result.reference_keyframe = reference;
      result.timings.keyframe_ms = ms_since(t0);
      frames.push_back({frame.index, frame.timestamp, reference, Pose::Identity()});
      T_ref_last = Pose::Identity();
      {
        std::lock_guard<std::mutex> lock(mutex);
        ++stats.frames;
      }
      result.timings.total_ms = ms_since(t_start);
      return result;
    }

    // Keyframe poses corrected by the pose graph since the last frame: the velocity in world
    // terms is still valid, the reference pose is simply re-read below.
    uint64_t version;
    {
      std::lock_guard<std::mutex> lock(mutex);
      version = pose_version;
    }
    seen_version = version;

    const Pose prior = velocity_valid && !lost ? T_ref_last * velocity : T_ref_last;
    // A resumed map not yet relocalised into has no reference: straight to relocalisation.
    Registration reg = reference >= 0 ? register_to_reference(features, frame_pyramid, prior, frame.index, result)
                                      : Registration{};
    result.feature_matches = reg.matches;
    result.ransac_inliers = reg.inliers;
    result.used_motion_prior = reg.used_prior;
    bool ok = reg.accepted;
    if (std::getenv("SEMAP_TRACKING_DEBUG"))
      std::fprintf(stderr, "[tracker] frame %zu ref %d ok %d acc %d sup %d conv %d rmse %.4f overlap %.3f matches %d inliers %d prior %d prior_t %.3f reg_t %.3f\n",
                   frame.index, reference, int(reg.ok), int(reg.accepted), int(reg.feature_supported),
                   int(reg.icp.converged), reg.icp.rmse, reg.icp.overlap, reg.matches, reg.inliers, int(reg.used_prior),
                   prior.translation().norm(), reg.T_kf_frame.translation().norm());
    // Fern code only when used (relocalisation, keyframes, dissimilarity test): not per frame.
    FernCode code;
    auto fern_code = [&]() -> const FernCode& {
      if (code.empty()) code = ferns.encode(rgb, depth);
      return code;
    };
    t0 = Clock::now();
    TrackingStatus status = TrackingStatus::ok;
    if (!ok) {
      if (relocalise(features, frame_pyramid, fern_code(), reg)) {
        status = TrackingStatus::relocalised;
        ok = true;
        std::lock_guard<std::mutex> lock(mutex);
        ++stats.relocalisations;
      } else {
        status = TrackingStatus::lost;
      }
    }
    if (!ok) {
      // Hold the last pose relative to the current reference until relocalised.
      lost = true;
      velocity_valid = false;
      frames.push_back({frame.index, frame.timestamp, reference, T_ref_last});
      {
        std::lock_guard<std::mutex> lock(mutex);
        ++stats.lost_frames;
        ++stats.frames;
        if (reference < 0) ++stats.held_frames;  // a resumed map not relocalised into yet: no pose
        result.T_world_camera = reference >= 0 ? kf_pose.at(reference) * T_ref_last : Pose::Identity();
      }
      result.status = status;
      result.reference_keyframe = reference;
      result.timings.keyframe_ms = ms_since(t0);
      result.timings.total_ms = ms_since(t_start);
      return result;
    }
    lost = false;
    result.icp_matched = reg.icp.matched;
    result.icp_rmse = reg.icp.rmse;
    result.icp_overlap = reg.icp.overlap;

    Pose T_ref_frame = reg.T_kf_frame;
    // Keyframe decision: motion, overlap, weakening evidence (residual, feature support: renew
    // the keyframe while the registration still holds, issue 16) or fern dissimilarity (A3).
    const bool far = T_ref_frame.translation().norm() > cfg.keyframe_translation ||
                     deg(rotation_angle(T_ref_frame)) > cfg.keyframe_rotation_deg ||
                     reg.icp.overlap < cfg.keyframe_min_overlap || reg.icp.rmse > cfg.keyframe_max_icp_rmse ||
                     reg.inliers < cfg.keyframe_min_inliers;
    bool dissimilar = false;
    if (!far && cfg.fern_new_keyframe_similarity > 0) {  // similarity >= 0 always: test off at 0
      fern_code();
      std::lock_guard<std::mutex> lock(mutex);
      dissimilar = ferns.max_similarity(code) < cfg.fern_new_keyframe_similarity;
    }
    if (far || dissimilar) {
      Pose T_world_frame;
      {
        std::lock_guard<std::mutex> lock(mutex);
        T_world_frame = kf_pose.at(reference) * T_ref_frame;
      }
      if (!(cfg.keyframe_reuse && reuse_keyframe(features, frame_pyramid, T_world_frame, reg, T_ref_frame))) {
        fern_code();
        make_keyframe(frame, depth, gray, std::move(features), std::move(code), std::move(frame_pyramid), reference,
                      T_ref_frame, reg.icp);
        result.is_keyframe = true;
        T_ref_frame = Pose::Identity();
      }
    }
    result.timings.keyframe_ms = ms_since(t0);

    frames.push_back({frame.index, frame.timestamp, reference, T_ref_frame});
    {
      std::lock_guard<std::mutex> lock(mutex);
      result.T_world_camera = kf_pose.at(reference) * T_ref_frame;
      // Velocity from consecutive world poses (both read with the same keyframe poses).
      // A resumed map's first frame may relocalise at once: then there is no previous frame.
      const FrameRecord* prev = frames.size() >= 2 ? &frames[frames.size() - 2] : nullptr;
      velocity_valid = prev && prev->reference >= 0;
      if (velocity_valid) velocity = (kf_pose.at(prev->reference) * prev->T_ref_frame).inverse() * result.T_world_camera;
      ++stats.frames;
    }
    T_ref_last = T_ref_frame;
    result.status = status;
    result.reference_keyframe = reference;
    result.timings.total_ms = ms_since(t_start);
    return result;
  }

  void make_keyframe(const Frame& frame, const cv::Mat& depth, const cv::Mat& gray, FrameFeatures features, FernCode code,
                     std::vector<DepthLevel> frame_pyramid, int parent, const Pose& T_parent_this,
                     const IcpResult& icp) {
    auto kf = std::make_shared<Keyframe>();
    kf->frame_index = frame.index;
    kf->timestamp = frame.timestamp;
    kf->depth = depth.clone();
    kf->gray = gray.clone();
    kf->features = std::move(features);
    kf->code = std::move(code);
    kf->parent = parent;
    kf->T_parent_this = T_parent_this;
    int id;
    {
      std::lock_guard<std::mutex> lock(mutex);
      id = int(keyframes.size());
      kf->id = id;
      const Pose pose = parent >= 0 ? kf_pose.at(parent) * T_parent_this : Pose::Identity();
      kf_pose[id] = pose;
      keyframes.push_back(kf);
      if (parent >= 0) {
        PoseGraphEdge edge;
        edge.from = parent;
        edge.to = id;
        edge.T_from_to = T_parent_this;
        edge.information = edge_information(icp);
        graph.add_edge(edge);
      }
      ferns.add(id, kf->code);
      ++stats.keyframes;
    }
    reference = id;
    ref_pyramid = std::move(frame_pyramid);
    complete_target_pyramid(ref_pyramid, true);
    remember_target(id, ref_pyramid);
    submit_keyframe(id);
  }

  /// Tracks against an older keyframe near the current pose instead of adding a new one
  /// (bounds drift when the camera returns); adds a graph edge old reference -> reused.
  bool reuse_keyframe(const FrameFeatures& features, const std::vector<DepthLevel>& frame_pyramid,
                      const Pose& T_world_frame, const Registration& current, Pose& T_ref_frame) {
    int best = -1;
    double best_score = cfg.keyframe_reuse_max_score;
    std::shared_ptr<const Keyframe> best_kf;
    Pose best_pose;
    {
      std::lock_guard<std::mutex> lock(mutex);
      for (const auto& [id, pose] : kf_pose) {
        if (id == reference) continue;
        const double score = keyframe_score(pose.inverse() * T_world_frame);
        if (score < best_score) {
          best_score = score;
          best = id;
          best_pose = pose;
        }
      }
      if (best >= 0) best_kf = keyframes[best];
    }
    if (best < 0) return false;
    const auto kf_pyramid = pyramid(best_kf->depth, best_kf->gray);
    const Pose guess = best_pose.inverse() * T_world_frame;
    const IcpResult icp = icp_point_to_plane(frame_pyramid, kf_pyramid, guess, icp_params);
    if (!icp_acceptable(icp, cfg.loss_max_icp_rmse, cfg.keyframe_min_overlap)) return false;
    const Pose jump = guess.inverse() * icp.T_target_source;
    if (jump.translation().norm() > cfg.loss_max_translation_jump ||
        deg(rotation_angle(jump)) > cfg.loss_max_rotation_jump_deg)
      return false;
    {
      std::lock_guard<std::mutex> lock(mutex);
      PoseGraphEdge edge;
      edge.from = reference;
      edge.to = best;
      edge.T_from_to = current.T_kf_frame * icp.T_target_source.inverse();
      // The chained measurement is no better than the weaker of its two registrations.
      const Matrix6d a = edge_information(current.icp), b = edge_information(icp);
      edge.information = a.trace() < b.trace() ? a : b;
      graph.add_edge(edge);
      ++stats.keyframe_reuses;
    }
    reference = best;
    ref_pyramid = kf_pyramid;
    remember_target(best, ref_pyramid);
    T_ref_frame = icp.T_target_source;
    return true;
  }

  /// Keyframes a lost frame is registered against: the most similar by ferns (A3), the most
  /// recent ones and the reference (the camera is usually still near where it was lost).
  std::vector<std::shared_ptr<const Keyframe>> relocalisation_candidates(const FernCode& code) const {
    std::vector<std::shared_ptr<const Keyframe>> out;
    auto add = [&](const std::shared_ptr<const Keyframe>& kf) {
      if (std::find(out.begin(), out.end(), kf) == out.end()) out.push_back(kf);
    };
    const auto similar = most_similar_keyframes(code);
    std::lock_guard<std::mutex> lock(mutex);
    if (reference >= 0) add(keyframes[reference]);
    for (const auto& kf : similar) add(kf);
    for (int i = 0; i < cfg.relocalisation_recent && i < int(keyframes.size()); ++i) add(keyframes[keyframes.size() - 1 - i]);
    return out;
  }

  /// The relocalisation_candidates keyframes most similar to `code` by ferns (A3), best first.
  std::vector<std::shared_ptr<const Keyframe>> most_similar_keyframes(const FernCode& code) const {
    std::vector<std::pair<double, std::shared_ptr<const Keyframe>>> by_fern;
    std::lock_guard<std::mutex> lock(mutex);
    const auto sims = ferns.similarities(code);
    for (size_t i = 0; i < sims.size(); ++i) by_fern.emplace_back(sims[i], keyframes[ferns.ids()[i]]);
    std::stable_sort(by_fern.begin(), by_fern.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    std::vector<std::shared_ptr<const Keyframe>> out;
    for (int i = 0; i < int(by_fern.size()) && i < cfg.relocalisation_candidates; ++i) out.push_back(by_fern[i].second);
    return out;
  }

  /// Wide-baseline registration judged as relocalise() judges it: no prior, feature support,
  /// enough overlap.
  bool relocalisation_accepted(const Registration& reg) const {
    return reg.accepted && reg.icp.overlap >= cfg.relocalisation_min_overlap;
  }

  /// Registers a lost frame against candidate keyframes (A3) with the wide-baseline effort; only
  /// a feature-supported registration with enough overlap counts (there is no prior to check).
  bool relocalise(const FrameFeatures& features, const std::vector<DepthLevel>& frame_pyramid,
                  const FernCode& code, Registration& out) {
    if (int(features.points.size()) < cfg.ransac_trusted_inliers) return false;  // blank / textureless frame
    for (const auto& kf : relocalisation_candidates(code)) {
      auto kf_pyramid = kf->id == reference ? ref_pyramid : pyramid(kf->depth, kf->gray);
      Registration reg = register_to(features, frame_pyramid, kf->features, kf_pyramid, nullptr,
                                     uint32_t(cfg.seed) + 104729u * uint32_t(kf->id + 1), Effort::wide);
      if (!relocalisation_accepted(reg)) continue;
      out = reg;
      reference = kf->id;
      ref_pyramid = std::move(kf_pyramid);
      remember_target(reference, ref_pyramid);
      velocity_valid = false;
      return true;
    }
    return false;
  }

  Trajectory trajectory_locked() const {
    Trajectory out;
    out.reserve(frames.size());
    for (const auto& f : frames)
      if (f.reference >= 0) out.push_back({f.timestamp, orthonormalized(kf_pose.at(f.reference) * f.T_ref_frame)});
    return out;
  }
};

Tracker::Tracker(const TrackingConfig& config, const CameraModel& camera)
    : impl_(std::make_unique<Impl>(config, camera)) {
  if (camera.has_distortion())  // the readers and the Mapper undistort before tracking (core/lens_undistortion.hpp)
    throw Error("Tracker", "takes undistorted (pinhole) frames; the camera has lens distortion");
}
Tracker::~Tracker() = default;

TrackResult Tracker::track(const Frame& frame) { return impl_->track(frame); }

Trajectory Tracker::finish() {
  if (impl_->cfg.background_loop_closure) impl_->wait_idle();
  if (impl_->cfg.pose_graph) impl_->optimise();
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->trajectory_locked();
}

Trajectory Tracker::trajectory() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->trajectory_locked();
}

std::vector<KeyframeInfo> Tracker::keyframes() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  std::vector<KeyframeInfo> out;
  for (const auto& kf : impl_->keyframes)
    out.push_back({kf->id, kf->frame_index, kf->timestamp, impl_->kf_pose.at(kf->id)});
  return out;
}

TrackerStats Tracker::stats() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  TrackerStats s = impl_->stats;
  s.keyframes = impl_->keyframes.size();
  return s;
}

const TrackingConfig& Tracker::config() const { return impl_->cfg; }

TrackerState Tracker::state() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  TrackerState out;
  out.keyframes = impl_->keyframes;
  for (const auto& kf : impl_->keyframes) out.T_world_keyframe.push_back(impl_->kf_pose.at(kf->id));
  out.edges = impl_->graph.edges();
  return out;
}

std::optional<KeyframeMatch> Tracker::match_keyframe(const Keyframe& other) const {
  const Impl& t = *impl_;
  if (int(other.features.points.size()) < t.cfg.ransac_trusted_inliers) return std::nullopt;  // textureless view
  const auto other_pyramid = t.pyramid(other.depth, other.gray, true);
  for (const auto& kf : t.most_similar_keyframes(other.code)) {
    const Registration reg = t.register_to(other.features, other_pyramid, kf->features, t.pyramid(kf->depth, kf->gray),
                                           nullptr, uint32_t(t.cfg.seed) + 104729u * uint32_t(kf->id + 1), Effort::wide);
    if (!t.relocalisation_accepted(reg)) continue;
    KeyframeMatch match;
    match.keyframe_id = kf->id;
    match.T_keyframe_other = reg.T_kf_frame;
    {
      std::lock_guard<std::mutex> lock(t.mutex);
      match.T_world_other = orthonormalized(t.kf_pose.at(kf->id) * reg.T_kf_frame);
    }
    match.information = t.edge_information(reg.icp);
    match.inliers = reg.inliers;
    match.overlap = reg.icp.overlap;
    match.rmse_m = reg.icp.rmse;
    return match;
  }
  return std::nullopt;
}

void Tracker::resume(const TrackerState& state) {
  Impl& t = *impl_;
  if (!t.frames.empty() || !t.keyframes.empty()) throw Error("Tracker::resume", "must be called before the first frame");
  if (state.keyframes.empty()) throw Error("Tracker::resume", "the saved map has no keyframes to relocalise against");
  for (const auto& kf : state.keyframes)
    if (kf->depth.cols != t.intr.width || kf->depth.rows != t.intr.height)
      throw Error("Tracker::resume", "the saved map's keyframes are " + std::to_string(kf->depth.cols) + "x" +
                                         std::to_string(kf->depth.rows) + ", this camera's depth is " +
                                         std::to_string(t.intr.width) + "x" + std::to_string(t.intr.height));
  std::lock_guard<std::mutex> lock(t.mutex);
  t.keyframes = state.keyframes;
  for (size_t i = 0; i < state.keyframes.size(); ++i) {
    t.kf_pose[int(i)] = state.T_world_keyframe[i];
    t.ferns.add(int(i), state.keyframes[i]->code);
  }
  for (const PoseGraphEdge& e : state.edges) t.graph.add_edge(e);
  t.resumed_keyframes = int(state.keyframes.size());
  t.stats.resumed_keyframes = state.keyframes.size();
  t.lost = true;
}

}  // namespace semap
