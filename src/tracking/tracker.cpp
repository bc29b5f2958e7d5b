#include "tracking/tracker.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <optional>
#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"
#include "tracking/depth_repair.hpp"
#include "tracking/keyframe_database.hpp"
#include "tracking/loop_closer.hpp"
#include "tracking/lost_frame_poses.hpp"
#include "tracking/odometry.hpp"
#include "tracking/parallel.hpp"
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

TrackingConfig validated(const TrackingConfig& config) {
  config.validate();
  return config;
}

struct FrameRecord {
  size_t frame_index = 0;
  double timestamp = 0.0;
  int reference = 0;
  Pose T_ref_frame = Pose::Identity();
  bool lost = false;  ///< held at the last verified pose (lost_frame_poses.hpp)
};

/// What track() derives from a frame before registering it.
struct FrameInput {
  cv::Mat rgb, gray, depth;  ///< colour at depth resolution, its grey image, repaired depth
  FrameFeatures features;
  std::vector<DepthLevel> pyramid;  ///< source-only ICP pyramid
  FernCode code;                    ///< computed when first needed (fern_code)
  std::optional<FrameFeatures> wide_features;  ///< the wide-baseline set, when first needed
};
}  // namespace

/// The tracking thread's state and the three parts. Member order matters: the LoopCloser is
/// destroyed first (joins its worker while the database and the odometry still exist).
struct Tracker::Impl {
  TrackingConfig cfg;
  PinholeIntrinsics intr;
  Odometry odometry;
  KeyframeDatabase keyframes;
  LoopCloser loop;

  // Per-frame state: the tracking thread (track(), resume()) only.
  int reference = -1;                 ///< keyframe the frames are registered against
  std::vector<DepthLevel> ref_pyramid;  ///< its completed ICP target pyramid
  std::optional<FrameFeatures> ref_wide_features;  ///< its wide-baseline set, once extracted
  Pose T_ref_last = Pose::Identity();
  Pose velocity = Pose::Identity();  ///< T_{k-2}^{-1} T_{k-1}
  bool velocity_valid = false;
  bool lost = false;
  int resumed_keyframes = 0;  ///< keyframes 0..n-1 came from a saved map (resume): fixed, relocalised into
  std::shared_ptr<const ModelView> model;  ///< the fused model (set_model_view), or none

  // Written by the tracking thread, read by trajectory() / stats() from any thread.
  mutable std::mutex frames_mutex;
  std::vector<FrameRecord> frames;
  TrackerStats counters;  ///< the per-frame counts (keyframes, loop edges: from the parts)

  Impl(const TrackingConfig& c, const CameraModel& camera)
      : cfg(validated(c)), intr(camera.depth), odometry(cfg, intr), keyframes(cfg, odometry),
        loop(cfg, odometry, keyframes) {}

  // --- the steps of track() ---
  void check_frame(const Frame& frame) const {
    if (frame.depth.empty() || frame.depth.type() != CV_32FC1)
      throw Error(frame.depth_path.empty() ? "Tracker::track" : frame.depth_path, "depth must be CV_32FC1 metres");
    if (frame.rgb.empty() || frame.rgb.type() != CV_8UC3)
      throw Error(frame.rgb_path.empty() ? "Tracker::track" : frame.rgb_path, "rgb must be CV_8UC3");
    if (frame.depth.cols != intr.width || frame.depth.rows != intr.height)
      throw Error(frame.depth_path.empty() ? "Tracker::track" : frame.depth_path, "depth size differs from the camera model");
  }

  /// A1 depth repair, A2 features and the source pyramid.
  FrameInput prepare_frame(const Frame& frame, TrackResult& result) {
    FrameInput in;
    in.rgb = frame.rgb;
    if (in.rgb.size() != frame.depth.size()) cv::resize(frame.rgb, in.rgb, frame.depth.size(), 0, 0, cv::INTER_AREA);
    cv::cvtColor(in.rgb, in.gray, cv::COLOR_BGR2GRAY);
    auto t0 = Clock::now();
    in.depth = cfg.depth_repair.enabled ? repair_depth(frame.depth, in.gray, cfg.depth_repair) : frame.depth;
    result.depth = in.depth;  // the frame's own pixel grid (the map integrates it with the colour)
    result.timings.repair_ms = ms_since(t0);
    t0 = Clock::now();
    in.features = odometry.extract_features(in.gray, in.depth);
    in.pyramid = odometry.pyramid(in.depth, in.gray, /*source_only=*/true);
    result.timings.features_ms = ms_since(t0);
    return in;
  }

  /// Fern code only when used (relocalisation, keyframes, dissimilarity test): not per frame.
  const FernCode& fern_code(FrameInput& in) const {
    if (in.code.empty()) in.code = keyframes.encode(in.rgb, in.depth);
    return in.code;
  }

  /// The first frame: world = its camera.
  void start_map(const Frame& frame, FrameInput& in, TrackResult& result) {
    const auto t0 = Clock::now();
    fern_code(in);
    make_keyframe(frame, in, -1, Pose::Identity(), IcpResult{});
    result.is_keyframe = true;
    result.reference_keyframe = reference;
    result.timings.keyframe_ms = ms_since(t0);
    record_frame(frame, Pose::Identity(), /*lost=*/false);
    T_ref_last = Pose::Identity();
  }

  Pose motion_prior() const { return velocity_valid && !lost ? T_ref_last * velocity : T_ref_last; }

  /// The keyframe the frames are registered against from now on, with its target pyramid and,
  /// when the frame that became it had one, its wide-baseline feature set.
  void set_reference(int id, std::vector<DepthLevel> pyramid, std::optional<FrameFeatures> wide = std::nullopt) {
    reference = id;
    ref_pyramid = std::move(pyramid);
    ref_wide_features = std::move(wide);
    keyframes.remember_target(id, ref_pyramid);
  }

  /// The wide-baseline feature sets (issue 42), extracted only when first needed: a wide
  /// baseline leaves too few of the per-frame keypoints in common to register.
  const FrameFeatures& wide_features(FrameInput& in) {
    if (!in.wide_features) in.wide_features = odometry.extract_wide_features(in.gray, in.depth);
    return *in.wide_features;
  }
  const FrameFeatures& reference_wide_features() {
    if (!ref_wide_features) {
      const std::shared_ptr<const Keyframe> ref_kf = keyframes.get(reference);
      ref_wide_features = odometry.extract_wide_features(ref_kf->gray, ref_kf->depth);
    }
    return *ref_wide_features;
  }

  /// Frame-to-reference registration from the motion prior; when that failed, the wide-baseline
  /// effort (more RANSAC samples, a wider ICP gate) with the per-frame features, then with the
  /// denser sets (issue 16: consecutive-frame speed stays as it was; issue 42: keyframe-rate
  /// baselines share too few of the per-frame keypoints). The first accepted one is kept.
  OdometryResult register_to_reference(FrameInput& in, const Pose& prior, size_t frame_index, TrackResult& result) {
    const std::shared_ptr<const Keyframe> ref_kf = keyframes.get(reference);
    const uint32_t seed = uint32_t(cfg.seed) + uint32_t(frame_index);
    OdometryResult reg = odometry.register_to(in.features, in.pyramid, ref_kf->features, ref_pyramid, &prior, seed);
    add_timings(reg, result);
    if (reg.accepted) return reg;
    const double step = velocity_valid && !lost ? pose_distance(Pose::Identity(), velocity) : 0.0;
    const uint32_t wide_seed = seed * 2654435761u + 17u;
    OdometryResult wide = odometry.register_to(in.features, in.pyramid, ref_kf->features, ref_pyramid, &prior,
                                               wide_seed, RegistrationEffort::wide, step);
    add_timings(wide, result);
    if (wide.accepted || cfg.orb_wide_features <= 0) return wide.accepted ? wide : reg;
    const auto t0 = Clock::now();
    const FrameFeatures& frame_dense = wide_features(in);
    const FrameFeatures& ref_dense = reference_wide_features();
    result.timings.features_ms += ms_since(t0);
    OdometryResult dense = odometry.register_to(frame_dense, in.pyramid, ref_dense, ref_pyramid, &prior, wide_seed,
                                                RegistrationEffort::wide, step);
    add_timings(dense, result);
    return dense.accepted ? dense : reg;
  }
  static void add_timings(const OdometryResult& reg, TrackResult& result) {
    result.timings.ransac_ms += reg.ransac_ms;
    result.timings.icp_ms += reg.icp_ms;
  }

  void report_registration(const OdometryResult& reg, const Pose& prior, size_t frame_index, TrackResult& result) {
    result.feature_matches = reg.matches;
    result.check = reg.check;
    count_checks(reg.check);
    result.ransac_inliers = reg.inliers;
    result.used_motion_prior = reg.used_prior;
    if (std::getenv("SEMAP_TRACKING_DEBUG"))
      std::fprintf(stderr, "[tracker] frame %zu ref %d ok %d acc %d sup %d conv %d rmse %.4f overlap %.3f matches %d inliers %d prior %d prior_t %.3f reg_t %.3f dense %.3f/%.3f/%.3f cells %d votes %d/%d eig %.4f\n",
                   frame_index, reference, int(reg.ok), int(reg.accepted), int(reg.feature_supported),
                   int(reg.icp.converged), reg.icp.rmse, reg.icp.overlap, reg.matches, reg.inliers, int(reg.used_prior),
                   prior.translation().norm(), reg.T_kf_frame.translation().norm(), reg.check.consistent_fraction,
                   reg.check.agreeing_share, reg.check.dense_overlap, reg.check.occupied_cells, reg.check.runner_up_votes, reg.inliers,
                   reg.check.min_information_eigenvalue);
  }

  /// Issue 42: how often each verification check fails (TrackerStats).
  void count_checks(const RegistrationCheck& check) {
    if (!check.evaluated) return;
    std::lock_guard<std::mutex> lock(frames_mutex);
    ++counters.verified_registrations;
    counters.dense_residual_failed += !check.dense_ok;
    counters.spread_failed += !check.spread_ok;
    counters.ambiguous_matches += check.ambiguous;
    counters.under_constrained += check.conditioning_evaluated && !check.well_conditioned;
  }

  /// A lost frame against the keyframe database (A3); on success the reference changes.
  bool relocalise(FrameInput& in, OdometryResult& reg) {
    auto found = keyframes.relocalise(in.features, in.pyramid, fern_code(in), reference, ref_pyramid);
    if (!found) return false;
    reg = std::move(found->registration);
    set_reference(found->keyframe->id, std::move(found->keyframe_pyramid));
    velocity_valid = false;
    std::lock_guard<std::mutex> lock(frames_mutex);
    ++counters.relocalisations;
    return true;
  }

  /// Holds the last pose relative to the current reference until relocalised.
  void hold_lost_frame(const Frame& frame, TrackResult& result) {
    lost = true;
    velocity_valid = false;
    result.T_world_camera = reference >= 0 ? loop.pose(reference) * T_ref_last : Pose::Identity();
    record_frame(frame, T_ref_last, /*lost=*/true);
    result.status = TrackingStatus::lost;
    result.reference_keyframe = reference;
  }

  /// Keyframe decision: motion, overlap, weakening evidence (residual, feature support: renew
  /// the keyframe while the registration still holds, issue 16) or fern dissimilarity (A3).
  bool needs_new_keyframe(const OdometryResult& reg, FrameInput& in) const {
    const Pose& T = reg.T_kf_frame;
    const bool far = T.translation().norm() > cfg.keyframe_translation ||
                     deg(rotation_angle(T)) > cfg.keyframe_rotation_deg || reg.icp.overlap < cfg.keyframe_min_overlap ||
                     reg.icp.rmse > cfg.keyframe_max_icp_rmse || reg.inliers < cfg.keyframe_min_inliers;
    if (far) return true;
    if (cfg.fern_new_keyframe_similarity <= 0) return false;  // similarity >= 0 always: test off at 0
    return keyframes.max_similarity(fern_code(in)) < cfg.fern_new_keyframe_similarity;
  }

  /// A verified frame: keyframe re-use or a new keyframe when needed, then its record and the
  /// velocity. Returns the frame's pose relative to the (possibly new) reference.
  void accept_frame(const Frame& frame, FrameInput& in, const OdometryResult& reg, TrackResult& result) {
    lost = false;
    result.icp_matched = reg.icp.matched;
    result.icp_rmse = reg.icp.rmse;
    result.icp_overlap = reg.icp.overlap;
    Pose T_ref_frame = reg.T_kf_frame;
    if (needs_new_keyframe(reg, in)) {
      const Pose T_world_frame = loop.pose(reference) * T_ref_frame;
      if (!(cfg.keyframe_reuse && reuse_keyframe(in, T_world_frame, reg, T_ref_frame))) {
        fern_code(in);
        make_keyframe(frame, in, reference, T_ref_frame, reg.icp);
        result.is_keyframe = true;
        T_ref_frame = Pose::Identity();
      }
    }
    // Velocity from consecutive world poses (both read with the same keyframe poses).
    // A resumed map's first frame may relocalise at once: then there is no previous frame.
    const FrameRecord* prev = frames.empty() ? nullptr : &frames.back();
    velocity_valid = prev && prev->reference >= 0;
    if (velocity_valid) {
      const auto poses = loop.poses({reference, prev->reference});
      result.T_world_camera = poses[0] * T_ref_frame;
      velocity = (poses[1] * prev->T_ref_frame).inverse() * result.T_world_camera;
    } else {
      result.T_world_camera = loop.pose(reference) * T_ref_frame;
    }
    record_frame(frame, T_ref_frame, /*lost=*/false);
    T_ref_last = T_ref_frame;
    result.reference_keyframe = reference;
  }

  void record_frame(const Frame& frame, const Pose& T_ref_frame, bool is_lost) {
    std::lock_guard<std::mutex> lock(frames_mutex);
    frames.push_back({frame.index, frame.timestamp, reference, T_ref_frame, is_lost});
    ++counters.frames;
    if (is_lost) {
      ++counters.lost_frames;
      if (reference < 0) ++counters.held_frames;  // a resumed map not relocalised into yet: no pose
    }
  }

  TrackResult track(const Frame& frame) {
    const auto t_start = Clock::now();
    const tracking_detail::SerialScope serial(!cfg.parallel);
    check_frame(frame);
    TrackResult result;
    result.frame_index = frame.index;
    result.timestamp = frame.timestamp;
    FrameInput in = prepare_frame(frame, result);
    if (reference < 0 && resumed_keyframes == 0) {
      start_map(frame, in, result);
    } else {
      const Pose prior = motion_prior();
      // A resumed map not yet relocalised into has no reference: straight to relocalisation.
      OdometryResult reg = reference >= 0 ? register_to_reference(in, prior, frame.index, result) : OdometryResult{};
      report_registration(reg, prior, frame.index, result);
      const auto t0 = Clock::now();
      const bool relocalised = !reg.accepted && relocalise(in, reg);
      if (reg.accepted) {
        result.status = relocalised ? TrackingStatus::relocalised : TrackingStatus::ok;
        accept_frame(frame, in, reg, result);
      } else {
        hold_lost_frame(frame, result);
      }
      result.timings.keyframe_ms = ms_since(t0);
    }
    result.timings.total_ms = ms_since(t_start);
    return result;
  }

  /// The frame becomes keyframe `size()`: a pose-graph vertex (with its odometry edge to
  /// `parent`), then an entry of the database, then the new reference; queued for loops.
  void make_keyframe(const Frame& frame, FrameInput& in, int parent, const Pose& T_parent_this, const IcpResult& icp) {
    auto kf = std::make_shared<Keyframe>();
    kf->id = int(keyframes.size());  // only this thread adds keyframes
    kf->frame_index = frame.index;
    kf->timestamp = frame.timestamp;
    kf->depth = in.depth.clone();
    kf->gray = in.gray.clone();
    kf->features = std::move(in.features);
    kf->code = std::move(in.code);
    kf->parent = parent;
    kf->T_parent_this = T_parent_this;
    const int id = kf->id;
    loop.add_keyframe(id, parent, T_parent_this, parent >= 0 ? odometry.information(icp) : Matrix6d::Zero());
    keyframes.add(std::move(kf));
    std::vector<DepthLevel> target = model_target(in, loop.pose(id));
    if (target.empty()) {
      target = std::move(in.pyramid);
      complete_target_pyramid(target, true);
    }
    set_reference(id, std::move(target), std::move(in.wide_features));
    loop.submit(id);
  }

  /// Frame-to-model (METHODS.md A2): the keyframe's ICP target pyramid from the model's surface
  /// along its pixel rays, its own depth where the model has none; empty without a model (or
  /// tracking.model_keyframes off). The map was fused with the poses of their time and the
  /// graph's pose of the keyframe may have moved since (loop closure): the keyframe is first
  /// registered to the model seen from that pose (not within the keyframe limits: no model), then
  /// the model is taken from where the keyframe fits it.
  std::vector<DepthLevel> model_target(const FrameInput& in, const Pose& T_world_keyframe) const {
    if (!model || !cfg.model_keyframes) return {};
    cv::Mat depth = model->surface_depth(in.depth, intr, T_world_keyframe);
    const IcpResult icp = odometry.refine(in.pyramid, odometry.pyramid(depth, in.gray), Pose::Identity());
    if (!odometry.icp_acceptable(icp, cfg.keyframe_max_icp_rmse, cfg.keyframe_min_overlap)) return {};
    depth = model->surface_depth(in.depth, intr, T_world_keyframe * icp.T_target_source);
    const cv::Mat unseen = depth <= 0;
    in.depth.copyTo(depth, unseen);
    return odometry.pyramid(depth, in.gray);
  }

  /// A registration to an older keyframe is a reference only when it would be kept as one
  /// (residual and overlap within the keyframe limits: a reference that already fails them is
  /// replaced at the next frame, after its pose entered the graph and the frame's trajectory)
  /// and verified like any registration (issue 42: dense residual, plausible against the
  /// chained pose). Reuses accepted at the loss limit (RMSE up to loss_max_icp_rmse) were
  /// followed by a new keyframe at once on TUM fr1_rpy and cost it 0.4 cm ATE, 0.5 deg/s RPE.
  bool reuse_verified(const FrameInput& in, const std::vector<DepthLevel>& kf_pyramid, const Pose& guess,
                      const IcpResult& icp) {
    if (!odometry.icp_acceptable(icp, cfg.keyframe_max_icp_rmse, cfg.keyframe_min_overlap)) return false;
    if (!odometry.plausible(guess, icp.T_target_source)) return false;
    const RegistrationCheck check = odometry.dense_check(in.pyramid, kf_pyramid, icp.T_target_source);
    count_checks(check);
    return check.dense_ok;
  }

  /// Tracks against an older keyframe near the current pose instead of adding a new one
  /// (bounds drift when the camera returns); adds a graph edge old reference -> reused.
  bool reuse_keyframe(const FrameInput& in, const Pose& T_world_frame, const OdometryResult& current, Pose& T_ref_frame) {
    int best = -1;
    double best_score = cfg.keyframe_reuse_max_score;
    Pose best_pose;
    for (const auto& [id, pose] : loop.all_poses()) {
      if (id == reference) continue;
      const double score = keyframe_spacings(pose.inverse() * T_world_frame, cfg);
      if (score < best_score) {
        best_score = score;
        best = id;
        best_pose = pose;
      }
    }
    if (best < 0) return false;
    const std::shared_ptr<const Keyframe> best_kf = keyframes.get(best);
    const auto kf_pyramid = odometry.pyramid(best_kf->depth, best_kf->gray);
    const Pose guess = best_pose.inverse() * T_world_frame;
    const IcpResult icp = odometry.refine(in.pyramid, kf_pyramid, guess);
    if (!reuse_verified(in, kf_pyramid, guess, icp)) return false;
    PoseGraphEdge edge;
    edge.from = reference;
    edge.to = best;
    edge.T_from_to = current.T_kf_frame * icp.T_target_source.inverse();
    // The chained measurement is no better than the weaker of its two registrations.
    const Matrix6d a = odometry.information(current.icp), b = odometry.information(icp);
    edge.information = a.trace() < b.trace() ? a : b;
    loop.add_edge(edge);
    {
      std::lock_guard<std::mutex> lock(frames_mutex);
      ++counters.keyframe_reuses;
    }
    set_reference(best, kf_pyramid);
    T_ref_frame = icp.T_target_source;
    return true;
  }

  Trajectory trajectory() const {
    std::vector<FrameRecord> records;
    {
      std::lock_guard<std::mutex> lock(frames_mutex);
      records = frames;
    }
    const std::map<int, Pose> poses = loop.all_poses();
    Trajectory out;
    std::vector<bool> verified;
    out.reserve(records.size());
    for (const auto& f : records) {
      if (f.reference < 0) continue;
      out.push_back({f.timestamp, orthonormalized(poses.at(f.reference) * f.T_ref_frame)});
      verified.push_back(!f.lost);
    }
    fill_lost_poses(out, verified, cfg.lost_pose_max_gap_s);
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

void Tracker::set_model_view(std::shared_ptr<const ModelView> model) { impl_->model = std::move(model); }

Trajectory Tracker::finish() {
  if (impl_->cfg.background_loop_closure) impl_->loop.wait_idle();
  if (impl_->cfg.pose_graph) impl_->loop.optimise();
  return impl_->trajectory();
}

Trajectory Tracker::trajectory() const { return impl_->trajectory(); }

std::vector<KeyframeInfo> Tracker::keyframes() const {
  std::vector<KeyframeInfo> out;
  for (const auto& kf : impl_->keyframes.all())
    out.push_back({kf->id, kf->frame_index, kf->timestamp, impl_->loop.pose(kf->id)});
  return out;
}

TrackerStats Tracker::stats() const {
  TrackerStats s;
  {
    std::lock_guard<std::mutex> lock(impl_->frames_mutex);
    s = impl_->counters;
  }
  s.keyframes = impl_->keyframes.size();
  const LoopClosureStats loop = impl_->loop.stats();
  s.loop_edges = loop.loop_edges;
  s.local_edges = loop.local_edges;
  s.optimisations = loop.optimisations;
  return s;
}

const TrackingConfig& Tracker::config() const { return impl_->cfg; }

TrackerState Tracker::state() const {
  TrackerState out;
  out.keyframes = impl_->keyframes.all();
  const std::map<int, Pose> poses = impl_->loop.all_poses();
  for (const auto& kf : out.keyframes) out.T_world_keyframe.push_back(poses.at(kf->id));
  const int n = int(out.keyframes.size());
  for (const PoseGraphEdge& e : impl_->loop.edges())  // edges of keyframes added meanwhile wait for the next state
    if (e.from < n && e.to < n) out.edges.push_back(e);
  return out;
}

std::optional<KeyframeMatch> Tracker::match_keyframe(const Keyframe& other) const {
  const auto found = impl_->keyframes.match(other);
  if (!found) return std::nullopt;
  const OdometryResult& reg = found->registration;
  KeyframeMatch match;
  match.keyframe_id = found->keyframe->id;
  match.T_keyframe_other = reg.T_kf_frame;
  match.T_world_other = orthonormalized(impl_->loop.pose(match.keyframe_id) * reg.T_kf_frame);
  match.information = impl_->odometry.information(reg.icp);
  match.inliers = reg.inliers;
  match.overlap = reg.icp.overlap;
  match.rmse_m = reg.icp.rmse;
  return match;
}

void Tracker::resume(const TrackerState& state) {
  Impl& t = *impl_;
  {
    std::lock_guard<std::mutex> lock(t.frames_mutex);
    if (!t.frames.empty() || t.keyframes.size() > 0) throw Error("Tracker::resume", "must be called before the first frame");
  }
  if (state.keyframes.empty()) throw Error("Tracker::resume", "the saved map has no keyframes to relocalise against");
  for (const auto& kf : state.keyframes)
    if (kf->depth.cols != t.intr.width || kf->depth.rows != t.intr.height)
      throw Error("Tracker::resume", "the saved map's keyframes are " + std::to_string(kf->depth.cols) + "x" +
                                         std::to_string(kf->depth.rows) + ", this camera's depth is " +
                                         std::to_string(t.intr.width) + "x" + std::to_string(t.intr.height));
  t.loop.resume(state.keyframes, state.T_world_keyframe, state.edges);  // poses first: see LoopCloser::add_keyframe
  for (const auto& kf : state.keyframes) t.keyframes.add(kf);
  t.resumed_keyframes = int(state.keyframes.size());
  {
    std::lock_guard<std::mutex> lock(t.frames_mutex);
    t.counters.resumed_keyframes = state.keyframes.size();
  }
  t.lost = true;
}

}  // namespace semap
