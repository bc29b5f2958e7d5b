#include "semap/mapper.hpp"

#include <spdlog/spdlog.h>

#include <atomic>
#include <condition_variable>
#include <mutex>

#include "semap/core/error.hpp"
#include "objects/object_mapper.hpp"
#include "core/archive.hpp"
#include "core/lens_undistortion.hpp"
#include "pipeline/map_archive.hpp"
#include "pipeline/map_refresh.hpp"
#include "pipeline/refresh_archive.hpp"
#include "pipeline/stage.hpp"
#include <opencv2/imgproc.hpp>

#include "pipeline/segmentation_channel.hpp"
#include "segmentation/groundtruth_segmenter.hpp"
#include "segmentation/panoptic_segmenter.hpp"
#include "segmentation/registration.hpp"
#include "semap/segmentation/segmenter_factory.hpp"
#include "segmentation/temporal_filter.hpp"
#include "tracking/depth_repair.hpp"
#include "tracking/tracker.hpp"
#include "tracking/tracker_state.hpp"
#include "tsdf/label_priors.hpp"
#include "tsdf/map_io.hpp"
#include "tsdf/tsdf_interpolation.hpp"
#include "tsdf/semantic_tsdf.hpp"
#include "tsdf/tsdf_raycast.hpp"
#include "tsdf/voxel_label.hpp"

namespace semap {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

/// A located frame on its way to fusion. `frame.index` is the Mapper's sequence number.
struct TrackedFrame {
  Frame frame;  ///< depth is the repaired depth used for tracking
  cv::Mat decoded_depth;  ///< the depth as given (before repair), for the refresh archive
  Pose T_world_camera;
  bool awaits_primary = false;   ///< the primary network's labels are on their way; fusion waits for them
  bool awaits_semantic = false;  ///< the same for a panoptic run's semantic network
  std::optional<SegmentationResult> primary_result, semantic_result;  ///< arrived (nullopt: dropped or failed)
  bool map_objects = false;  ///< its segmentation also feeds the object map (C2-C4)
  bool held = false;         ///< no pose yet (see FrameLog::held)
};

/// The fused TSDF as the tracker sees it (frame-to-model, METHODS.md A2; issue 42): one
/// read-only query, under the map's lock. Data flows one way: tracking never holds the map.
class TsdfModelView final : public ModelView {
 public:
  TsdfModelView(const SemanticTsdf& tsdf, std::mutex& tsdf_mutex) : tsdf_(tsdf), mutex_(tsdf_mutex) {}
  cv::Mat surface_depth(const cv::Mat& depth_m, const PinholeIntrinsics& intrinsics,
                        const Pose& T_world_camera) const override {
    std::lock_guard lock(mutex_);
    return surface_depth_along_rays(tsdf_.map(), depth_m, intrinsics, T_world_camera);
  }

 private:
  const SemanticTsdf& tsdf_;
  std::mutex& mutex_;
};

/// What fusion hands to the object map.
struct ObjectWork {
  Frame frame;
  SegmentationResult segmentation;
  Pose T_world_camera;
  bool keyframe = true;  ///< false: a segmented frame between object keyframes (ObjectMapper::accumulate)
};

/// What the Mapper remembers of every frame it was given.
struct FrameLog {
  size_t frame_index = 0;  ///< the caller's Frame::index
  double timestamp = 0.0;
  Pose T_world_camera_online = Pose::Identity();
  bool fused = false;
  bool held = false;  ///< a resumed map not relocalised into yet: no pose (Tracker::resume)
};

FrameStatus status_of(const TrackResult& r) {
  if (r.status == TrackingStatus::lost) return FrameStatus::lost;
  if (r.status == TrackingStatus::relocalised) return FrameStatus::relocalised;
  return r.is_keyframe ? FrameStatus::keyframe : FrameStatus::tracking;
}

DepthRepairParams repair_params(const TrackingConfig& c) {
  return c.depth_repair;
}

/// METHODS A1 guides the repair by the colour image at depth resolution; a separate colour
/// camera's image is resized for it, as the tracker does.
cv::Mat repaired(const cv::Mat& depth, const cv::Mat& rgb, const TrackingConfig& c) {
  if (rgb.empty() || rgb.size() == depth.size()) return repair_depth(depth, rgb, repair_params(c));
  cv::Mat resized;
  cv::resize(rgb, resized, depth.size(), 0, 0, cv::INTER_AREA);
  return repair_depth(depth, resized, repair_params(c));
}

std::unique_ptr<Segmenter> segmenter_from_config(const SemapConfig& config, const CameraModel& camera) {
  return make_segmenter(config.segmentation.segmenter, config.segmentation, camera);
}

/// `pipeline.threads: 1` promises every stage inline and byte-identical outputs: loop closure
/// too, whose background worker adds its edges at a frame that depends on thread timing.
SemapConfig with_inline_stages(SemapConfig config) {
  if (config.pipeline.threads == 1) config.tracking.background_loop_closure = false;
  return config;
}

}  // namespace

const char* to_string(FrameStatus status) {
  switch (status) {
    case FrameStatus::tracking: return "tracking";
    case FrameStatus::keyframe: return "keyframe";
    case FrameStatus::lost: return "lost";
    case FrameStatus::relocalised: return "relocalised";
  }
  return "?";
}

SegmentationResult segmentation_from_label_images(const cv::Mat& labels, const cv::Mat& instances) {
  return result_from_label_images(labels, instances);
}

struct Mapper::Impl {
  Impl(const SemapConfig& c, const CameraModel& given_camera, std::unique_ptr<Segmenter> seg)
      : config(with_inline_stages(c)),
        undistortion(given_camera),
        camera(LensUndistortion::pinhole(given_camera)),
        segmenter(seg ? std::move(seg) : segmenter_from_config(c, camera)),
        tsdf(c.tsdf),
        objects(c.objects, camera),
        temporal_filter(c.segmentation.temporal, camera.depth),
        repair_archive(camera.depth_scale, static_cast<size_t>(c.pipeline.refresh_cache_mb) << 20),
        frame_archive(static_cast<size_t>(c.pipeline.refresh_cache_mb) << 20) {
    const bool threaded = c.pipeline.threads > 1;
    const auto queue = static_cast<size_t>(c.pipeline.queue_size);
    objects_stage = std::make_unique<Stage<ObjectWork>>(threaded, queue, [this](ObjectWork& w) { map_objects(w); });
    fusion_stage = std::make_unique<Stage<TrackedFrame>>(
        threaded, queue, [this](TrackedFrame& f) { on_located(f); }, [this] { fuse_waiting(true); });
    make_segmentation_channels();
  }

  // --- tracking (caller's thread) ---
  void check_frame(const Frame& frame) const;
  TrackedFrame locate(const Frame& frame, const std::optional<Pose>& given, FrameResult& result);
  // --- segmentation ---
  void make_segmentation_channels();
  void schedule_segmentation(TrackedFrame& item, bool keyframe, std::optional<SegmentationResult> given);
  void on_segmentation_failure(const std::string& what);
  // --- fusion (fusion stage) ---
  void on_located(TrackedFrame& item);
  void fuse_waiting(bool block);
  bool collect_segmentation(TrackedFrame& item, bool block);
  std::optional<SegmentationResult> combined_segmentation(TrackedFrame& item) const;
  void fuse(TrackedFrame& item, const std::optional<SegmentationResult>& seg);
  void register_colour(Frame& frame) const;
  void archive_for_refresh(const TrackedFrame& item);
  void hand_to_objects(TrackedFrame& item, SegmentationResult seg);
  void map_objects(ObjectWork& work);
  // --- saved maps (issue 19) ---
  ArchiveSections sections() const;
  void restore(const ArchiveSections& sections, const std::filesystem::path& path);
  SemanticTsdf refresh_start() const;
  /// The tracker, handed the fused map as its model view (frame-to-model, METHODS.md A2).
  void make_tracker() {
    tracker = std::make_unique<Tracker>(config.tracking, camera);
    tracker->set_model_view(std::make_shared<TsdfModelView>(tsdf, tsdf_mutex));
  }
  // --- finish ---
  Trajectory current_trajectory() const;
  void refresh_map(const Trajectory& optimised);
  std::optional<IntegrationInput> refresh_input(size_t sequence, const Pose& T_world_camera) const;

  const SemapConfig config;
  const LensUndistortion undistortion;  ///< of the given camera; frames are undistorted where they enter
  const CameraModel camera;             ///< the pinhole camera every stage works with
  std::unique_ptr<Segmenter> segmenter;
  std::unique_ptr<Tracker> tracker;  ///< made at the first frame unless the caller gives poses
  std::optional<bool> external_poses;
  mutable std::mutex tracker_mutex;
  mutable SemanticTsdf tsdf;  ///< meshing is incremental (mutates the mesher), under tsdf_mutex
  mutable std::mutex tsdf_mutex;
  ObjectMapper objects;
  mutable std::mutex objects_mutex;
  TemporalLabelFilter temporal_filter;  ///< fusion thread only (sees frames in order)
  LabelArchive label_archive;
  RepairArchive repair_archive;
  FrameArchive frame_archive;
  FrameReloader reloader;
  StageTimings timings;
  double integration_workers_ms = 0;  ///< fusion thread: the integrator's worker CPU already charged
  mutable std::mutex log_mutex;
  std::vector<FrameLog> log;  ///< index = sequence number
  std::vector<FrameResult> frame_results;  ///< under log_mutex: what add_frame returned (issue 43)
  std::string first_segmentation_error;  ///< under log_mutex
  std::map<size_t, TrackedFrame> waiting;  ///< fusion thread: frames held until their labels arrive
  std::atomic<size_t> frames_fused{0}, object_frames{0}, skipped_accumulations{0};
  double min_instance_score = 0.0;  ///< panoptic: instances that overwrite the semantic labels
  std::atomic<size_t> objects_in_map{0};
  MapperStats final_stats;  ///< the parts only finish() knows
  std::string config_yaml;  ///< the config section (the loaded file's text when it came with the map)
  std::string saved_tsdf;   ///< a loaded map's TSDF section: the map refresh starts from it
  std::filesystem::path saved_path;
  bool finished = false;
  Trajectory final_trajectory;
  // Stages last: destroyed first (segmentation, then fusion, then objects), each drained.
  std::unique_ptr<Stage<ObjectWork>> objects_stage;
  std::unique_ptr<Stage<TrackedFrame>> fusion_stage;
  // The primary channel runs the segmenter (a panoptic one's instance network) and feeds the object
  // map; a panoptic run's semantic network has its own channel and schedule (issue 38).
  std::unique_ptr<SegmentationChannel> primary_channel, semantic_channel;
};

void Mapper::Impl::check_frame(const Frame& frame) const {
  const std::string where = frame.depth_path.empty() ? "frame " + std::to_string(frame.index) : frame.depth_path;
  if (finished) throw Error(where, "add_frame after finish()");
  const PinholeIntrinsics& d = camera.depth;
  if (frame.depth.type() != CV_32FC1 || frame.depth.cols != d.width || frame.depth.rows != d.height)
    throw Error(where, "depth must be CV_32FC1 metres of " + std::to_string(d.width) + "x" + std::to_string(d.height) +
                           " (the camera's depth size)");
  if (!frame.rgb.empty() && frame.rgb.type() != CV_8UC3)
    throw Error(frame.rgb_path.empty() ? where : frame.rgb_path, "colour must be CV_8UC3 (BGR)");
}

TrackedFrame Mapper::Impl::locate(const Frame& frame, const std::optional<Pose>& given, FrameResult& result) {
  if (!external_poses) external_poses = given.has_value();
  if (*external_poses != given.has_value())
    throw Error("frame " + std::to_string(frame.index),
                *external_poses ? "has no pose, but this Mapper was started with poses given by the caller"
                                : "has a pose, but this Mapper tracks (the first frame came without one)");
  TrackedFrame item;
  item.frame = frame;
  const StageStart t0 = StageStart::now();
  if (given) {
    if (!is_valid_pose(*given, 1e-4)) throw Error("frame " + std::to_string(frame.index), "pose is not a rigid transform");
    item.T_world_camera = *given;
    if (config.tracking.depth_repair.enabled) item.frame.depth = repaired(frame.depth, frame.rgb, config.tracking);
    timings.add("depth_repair", t0, frame.index);
    return item;
  }
  std::lock_guard lock(tracker_mutex);
  if (!tracker) make_tracker();
  const TrackResult r = tracker->track(frame);
  item.held = r.status == TrackingStatus::lost && r.reference_keyframe < 0;
  result.tracking_ms = t0.wall_ms_since();
  timings.add("tracking", t0, frame.index);
  item.T_world_camera = r.T_world_camera;
  result.status = status_of(r);
  result.ransac_inliers = r.ransac_inliers;
  item.decoded_depth = frame.depth;
  if (!r.depth.empty()) item.frame.depth = r.depth;
  return item;
}

void Mapper::Impl::make_segmentation_channels() {
  const SegmentationConfig& sc = config.segmentation;
  SegmentationChannel::Options options{"segmentation", {sc.every_n_frames, sc.on_keyframes}, config.pipeline.threads > 1,
                                       static_cast<size_t>(sc.async_queue_size), sc.when_busy};
  const auto on_failure = [this](const std::string& what) { on_segmentation_failure(what); };
  auto* panoptic = dynamic_cast<PanopticSegmenter*>(segmenter.get());
  Segmenter* primary = panoptic ? &panoptic->instance() : segmenter.get();
  primary_channel = std::make_unique<SegmentationChannel>(primary, options, timings, on_failure);
  if (!panoptic) return;
  min_instance_score = panoptic->min_instance_score();
  options.timing_name = "semantic_segmentation";
  options.schedule = {sc.panoptic.semantic_every_n_frames, sc.panoptic.semantic_on_keyframes};
  semantic_channel = std::make_unique<SegmentationChannel>(&panoptic->semantic(), options, timings, on_failure);
}

void Mapper::Impl::on_segmentation_failure(const std::string& what) {
  std::lock_guard lock(log_mutex);
  if (first_segmentation_error.empty()) first_segmentation_error = what;
}

void Mapper::Impl::schedule_segmentation(TrackedFrame& item, bool keyframe, std::optional<SegmentationResult> given) {
  const size_t sequence = item.frame.index;
  item.map_objects = primary_channel->schedule().wants(sequence, keyframe);
  if (given) {
    item.awaits_primary = true;
    primary_channel->put(sequence, std::move(given));
    return;
  }
  item.map_objects = item.map_objects && segmenter;
  item.awaits_primary = item.map_objects || (segmenter && segmenter->is_cheap());
  if (item.awaits_primary) primary_channel->send(item.frame);
  item.awaits_semantic = semantic_channel && semantic_channel->schedule().wants(sequence, keyframe);
  if (item.awaits_semantic) semantic_channel->send(item.frame);
}

void Mapper::Impl::on_located(TrackedFrame& item) {
  if (item.awaits_primary || item.awaits_semantic) {
    const size_t sequence = item.frame.index;
    waiting.emplace(sequence, std::move(item));
  } else {
    fuse(item, std::nullopt);
  }
  fuse_waiting(false);
}

void Mapper::Impl::fuse_waiting(bool block) {
  // In frame order: the object map and the temporal filter see frames as they were taken.
  while (!waiting.empty()) {
    auto it = waiting.begin();
    if (!collect_segmentation(it->second, block)) return;
    TrackedFrame item = std::move(it->second);
    waiting.erase(it);
    const bool to_objects = item.primary_result.has_value();  // semantic labels alone carry no instances
    std::optional<SegmentationResult> seg = combined_segmentation(item);
    fuse(item, seg);
    if (seg && to_objects) hand_to_objects(item, std::move(*seg));
  }
}

bool Mapper::Impl::collect_segmentation(TrackedFrame& item, bool block) {
  // One network's result, if it is awaited: false while it has not arrived (block: waits).
  const auto collect = [&](SegmentationChannel& channel, bool& awaits, std::optional<SegmentationResult>& into) {
    if (!awaits) return true;
    auto result = channel.take(item.frame.index, block);
    if (!result) return false;
    into = std::move(*result);
    awaits = false;
    return true;
  };
  return collect(*primary_channel, item.awaits_primary, item.primary_result) &&
         (!semantic_channel || collect(*semantic_channel, item.awaits_semantic, item.semantic_result));
}

std::optional<SegmentationResult> Mapper::Impl::combined_segmentation(TrackedFrame& item) const {
  if (!semantic_channel) return std::move(item.primary_result);
  // Panoptic (issue 38): the instances win inside their masks, the semantic labels fill the rest;
  // a frame only one network saw gets that network's labels.
  if (!item.primary_result) return std::move(item.semantic_result);
  SegmentationResult semantic = item.semantic_result ? std::move(*item.semantic_result) : SegmentationResult{};
  SegmentationResult out = combine_panoptic(std::move(semantic), *item.primary_result, min_instance_score);
  out.frame_index = item.frame.index;
  return out;
}

void Mapper::Impl::fuse(TrackedFrame& item, const std::optional<SegmentationResult>& seg) {
  const StageStart t0 = StageStart::now();
  register_colour(item.frame);
  IntegrationInput input = make_integration_input(item.frame, camera.depth, item.T_world_camera);
  input.labels = cv::Mat();
  if (seg && seg->has_labels()) {
    input.labels = temporal_filter.apply(seg->labels, item.frame.depth, item.T_world_camera);
    input.confidence = seg->confidence;
    input.probabilities = seg->probabilities;
    if (!*external_poses) label_archive.store(item.frame.index, input.labels);  // only a tracked run refreshes
  }
  double workers_ms = 0;  // the integrator's TBB workers since the last frame (issue 20 budget)
  {
    std::lock_guard lock(tsdf_mutex);
    tsdf.integrate(input);
    const double seen = tsdf.integrator().worker_cpu_ms();
    workers_ms = seen - std::min(integration_workers_ms, seen);  // a refreshed TSDF starts at 0
    integration_workers_ms = seen;
  }
  archive_for_refresh(item);
  ++frames_fused;
  timings.add("tsdf_integration", t0, item.frame.index, workers_ms);
}

void Mapper::Impl::register_colour(Frame& frame) const {
  // METHODS B2: colour sampled at depth pixels, so that the TSDF colour layer and the object
  // points get the colour of the surface each depth pixel saw.
  if (frame.rgb.empty() || !needs_registration(camera)) return;
  frame.rgb = register_image(frame.rgb, colour_lookup_map(frame.depth, camera), cv::INTER_LINEAR);
}

void Mapper::Impl::hand_to_objects(TrackedFrame& item, SegmentationResult seg) {
  ObjectWork work{std::move(item.frame), std::move(seg), item.T_world_camera, item.map_objects};
  if (work.keyframe) return objects_stage->push(std::move(work));
  if (!objects.accumulates()) return;
  // Points between object keyframes are best effort when the policy lets the stages drop work.
  if (config.segmentation.when_busy == WhenBusy::wait) return objects_stage->push(std::move(work));
  if (!objects_stage->try_push(work)) ++skipped_accumulations;
}

void Mapper::Impl::map_objects(ObjectWork& work) {
  const StageStart t0 = StageStart::now();
  std::lock_guard lock(objects_mutex);
  if (!work.keyframe) {
    objects.accumulate(work.frame, work.segmentation, work.T_world_camera);
    timings.add("object_accumulate", t0, work.frame.index);
    return;
  }
  objects.process(work.frame, work.segmentation, work.T_world_camera);
  timings.add("object_map", t0, work.frame.index);
  ++object_frames;
  objects_in_map = objects.instances().size();
}

void Mapper::Impl::archive_for_refresh(const TrackedFrame& item) {
  if (*external_poses) return;  // only a tracked run refreshes
  const StageStart t0 = StageStart::now();
  if (reloader) {
    // The reloader gives the frame as read; what depth repair filled is kept so that the
    // refresh need not repair again (A1), nor decode colour without a colour layer.
    repair_archive.store(item.frame.index, item.decoded_depth, item.frame.depth);
  } else {
    frame_archive.store(item.frame.index, item.frame.depth, config.tsdf.colour_layer ? item.frame.rgb : cv::Mat());
  }
  timings.add("refresh_archive", t0, item.frame.index);
}

Trajectory Mapper::Impl::current_trajectory() const {
  if (finished) return final_trajectory;
  if (tracker) {
    std::lock_guard lock(tracker_mutex);
    return tracker->trajectory();
  }
  std::lock_guard lock(log_mutex);
  Trajectory out;
  for (const FrameLog& f : log) out.push_back({f.timestamp, f.T_world_camera_online});
  return out;
}

std::optional<IntegrationInput> Mapper::Impl::refresh_input(size_t sequence, const Pose& T_world_camera) const {
  FrameLog entry;
  {
    std::lock_guard lock(log_mutex);
    entry = log[sequence];
  }
  if (!entry.fused) return std::nullopt;
  Frame frame;
  try {
    if (frame_archive.has(sequence)) {
      std::tie(frame.depth, frame.rgb) = frame_archive.load(sequence);
    } else if (reloader) {
      frame = reloader(entry.frame_index, config.tsdf.colour_layer || !repair_archive.has(sequence));
      undistortion.apply(frame);
      if (repair_archive.has(sequence)) {
        repair_archive.apply(sequence, frame.depth);
      } else if (config.tracking.depth_repair.enabled) {
        frame.depth = repaired(frame.depth, frame.rgb, config.tracking);
      }
    } else {
      return std::nullopt;
    }
  } catch (const Error& e) {
    spdlog::warn("map refresh: frame {} left out: {}", entry.frame_index, e.what());
    return std::nullopt;
  }
  frame.index = sequence;
  if (!frame_archive.has(sequence)) register_colour(frame);  // the archive keeps registered colour
  IntegrationInput input = make_integration_input(frame, camera.depth, T_world_camera);
  input.labels = label_archive.find(sequence);
  return input;
}

void Mapper::Impl::refresh_map(const Trajectory& optimised) {
  // Per frame, the correction T_optimised * T_online^-1 of the final pass and how far it moves a
  // surface point at the far end of the depth range.
  std::vector<FrameLog> frames;
  {
    std::lock_guard lock(log_mutex);
    frames = log;
  }
  // The tracker's trajectory leaves out held frames (no pose): align it with the log.
  std::vector<Pose> T_world_camera(frames.size(), Pose::Identity());
  size_t posed = 0;
  for (size_t k = 0; k < frames.size(); ++k)
    if (!frames[k].held && posed < optimised.size()) T_world_camera[k] = optimised[posed++].T_world_camera;
  if (posed != optimised.size() || posed + final_stats.held_frames != frames.size())
    throw Error("Mapper", "tracker returned a trajectory of another length");
  std::unordered_map<uint32_t, Eigen::Isometry3f> corrections;
  double max_displacement = 0.0;
  for (size_t k = 0; k < frames.size(); ++k) {
    // A lost frame was never fused, and its final pose is interpolated, not corrected.
    if (frames[k].held || !frames[k].fused) continue;
    const Pose& online = frames[k].T_world_camera_online;
    corrections[static_cast<uint32_t>(k)] = (T_world_camera[k] * online.inverse()).cast<float>();
    max_displacement = std::max(max_displacement, surface_displacement_m(online, T_world_camera[k], config.tsdf.max_depth));
  }
  final_stats.max_pose_correction_m = max_displacement;
  if (final_stats.loop_edges + final_stats.local_edges == 0) return;  // an odometry chain alone moves no pose
  {
    std::lock_guard lock(objects_mutex);
    objects.apply_pose_corrections(corrections);  // object points move with their frame
  }
  if (max_displacement <= 0.25 * config.tsdf.voxel_size) return;  // under a quarter voxel: keep the map
  const StageStart t0 = StageStart::now();
  size_t missing = 0;
  for (size_t k = 0; k < frames.size(); ++k)
    if (frames[k].fused && !frame_archive.has(k) && !reloader) ++missing;
  if (missing > 0) {
    final_stats.map_refresh_note = std::to_string(missing) +
                                   " frames were past pipeline.refresh_cache_mb and no frame reloader was set: "
                                   "the map keeps its online poses";
    spdlog::warn("map refresh skipped: {}", final_stats.map_refresh_note);
    return;
  }
  SemanticTsdf rebuilt = rebuild_tsdf(refresh_start(), frames.size(), config.pipeline.threads,
                                      [&](size_t k) { return refresh_input(k, T_world_camera[k]); });
  {
    std::lock_guard lock(tsdf_mutex);
    tsdf = std::move(rebuilt);
  }
  final_stats.map_refreshed = true;
  timings.add("map_refresh", t0, std::nullopt);
}

Mapper::Mapper(const SemapConfig& config, const CameraModel& camera, std::unique_ptr<Segmenter> segmenter) {
  config.validate();
  impl_ = std::make_unique<Impl>(config, camera, std::move(segmenter));
  impl_->config_yaml = encode_config_section(config);
}

Mapper::~Mapper() = default;

FrameResult Mapper::add_frame(const Frame& frame, FrameHints hints) {
  Impl& m = *impl_;
  const auto t0 = Clock::now();
  m.check_frame(frame);
  FrameResult result;
  result.frame_index = frame.index;
  result.timestamp = frame.timestamp;
  size_t sequence = 0;
  {
    std::lock_guard lock(m.log_mutex);
    sequence = m.log.size();
  }
  Frame own = frame;
  own.index = sequence;
  m.undistortion.apply(own);
  TrackedFrame item = m.locate(own, hints.T_world_camera, result);
  result.T_world_camera = item.T_world_camera;
  result.fused = result.status != FrameStatus::lost;  // a pose that failed its checks is never fused
  {
    std::lock_guard lock(m.log_mutex);
    m.log.push_back({frame.index, frame.timestamp, item.T_world_camera, result.fused, item.held});
  }
  if (result.fused) {
    m.schedule_segmentation(item, result.status == FrameStatus::keyframe, std::move(hints.segmentation));
    result.segmented = item.awaits_primary || item.awaits_semantic;
    m.fusion_stage->push(std::move(item));
  }
  result.total_ms = ms_since(t0);
  {
    std::lock_guard lock(m.log_mutex);
    m.frame_results.push_back(result);
  }
  return result;
}

void Mapper::finish() {
  Impl& m = *impl_;
  if (m.finished) return;
  m.primary_channel->close();
  if (m.semantic_channel) m.semantic_channel->close();
  m.fusion_stage->close();
  m.objects_stage->close();
  if (m.tracker) {
    const StageStart t0 = StageStart::now();
    Trajectory optimised;
    {
      std::lock_guard lock(m.tracker_mutex);
      optimised = m.tracker->finish();
      const TrackerStats tracked = m.tracker->stats();
      m.final_stats.loop_edges = tracked.loop_edges;
      m.final_stats.local_edges = tracked.local_edges;
      m.final_stats.held_frames = tracked.held_frames;
    }
    m.timings.add("pose_graph_final", t0, std::nullopt);
    m.refresh_map(optimised);
    m.final_trajectory = std::move(optimised);
  } else {
    m.final_trajectory = m.current_trajectory();
  }
  {
    const StageStart t0 = StageStart::now();
    std::lock_guard lock(m.objects_mutex);
    m.objects.finish();
    m.objects_in_map = m.objects.instances().size();
    const ObjectMapCounts counts = m.objects.counts();
    m.final_stats.objects_created = counts.created;
    m.final_stats.objects_deleted = counts.deleted;
    m.final_stats.objects_merged = counts.merged;
    m.timings.add("object_map_final", t0, std::nullopt);
  }
  m.finished = true;
}

void Mapper::set_frame_reloader(FrameReloader reloader) {
  {
    std::lock_guard lock(impl_->log_mutex);
    if (!impl_->log.empty()) throw Error("Mapper", "set_frame_reloader must be called before the first frame");
  }
  impl_->reloader = std::move(reloader);
}

Trajectory Mapper::trajectory() const { return impl_->current_trajectory(); }

TriangleMesh Mapper::mesh() const {
  TriangleMesh mesh;
  SurfaceLabelEvidence evidence;
  {
    std::lock_guard lock(impl_->tsdf_mutex);
    mesh = impl_->tsdf.extract_mesh();
    evidence = SurfaceLabelEvidence(impl_->tsdf.map(), mesh.vertices.points);
  }
  // Issue 38: labels that contradict their surface lose to those that fit (tsdf/label_priors.hpp).
  apply_label_priors(mesh, estimate_gravity(mesh, trajectory()), impl_->config.tsdf, evidence);
  std::lock_guard lock(impl_->objects_mutex);
  mesh.vertices.instances =
      impl_->objects.instance_ids_for(mesh.vertices.points, static_cast<float>(1.5 * impl_->config.tsdf.voxel_size));
  return mesh;
}

std::vector<ObjectSummary> Mapper::objects() const {
  // Exported points on the fused surface (objects.points_on_surface). Lock order: objects, then
  // tsdf (no other path holds both).
  std::lock_guard lock(impl_->objects_mutex);
  return impl_->objects.summaries([this](const std::vector<Eigen::Vector3f>& points) {
    std::lock_guard tsdf_lock(impl_->tsdf_mutex);
    ObjectMapper::SurfaceSamples surface;
    surface.points = project_onto_surface(impl_->tsdf.map(), points);
    surface.labels = surface_labels(impl_->tsdf.map(), surface.points);
    return surface;
  });
}

void Mapper::read_tsdf(const std::function<void(const TsdfMap&)>& reader) const {
  std::lock_guard lock(impl_->tsdf_mutex);
  reader(impl_->tsdf.map());
}

MapperStats Mapper::stats() const {
  const Impl& m = *impl_;
  MapperStats s = m.final_stats;
  {
    std::lock_guard lock(m.log_mutex);
    s.frames = m.log.size();
    s.segmentation_error = m.first_segmentation_error;
  }
  if (m.tracker) {
    std::lock_guard lock(m.tracker_mutex);
    const TrackerStats t = m.tracker->stats();
    s.keyframes = t.keyframes;
    s.lost_frames = t.lost_frames;
    s.relocalisations = t.relocalisations;
    s.loop_edges = t.loop_edges;
    s.local_edges = t.local_edges;
    s.optimisations = t.optimisations;
    s.resumed_keyframes = t.resumed_keyframes;
    s.held_frames = t.held_frames;
    s.verified_registrations = t.verified_registrations;
    s.dense_residual_failed = t.dense_residual_failed;
    s.spread_failed = t.spread_failed;
    s.ambiguous_matches = t.ambiguous_matches;
    s.under_constrained = t.under_constrained;
  }
  s.frames_fused = m.frames_fused;
  s.segmented_frames = m.primary_channel->segmented();
  s.segmentations_dropped = m.primary_channel->dropped();
  s.segmentations_failed = m.primary_channel->failed();
  if (m.semantic_channel) {
    s.semantic_segmented_frames = m.semantic_channel->segmented();
    s.segmentations_dropped += m.semantic_channel->dropped();
    s.segmentations_failed += m.semantic_channel->failed();
  }
  s.object_frames = m.object_frames;
  s.object_accumulations_skipped = m.skipped_accumulations;
  s.objects = m.objects_in_map;  // not the objects lock: the object stage may hold it for long
  s.finished = m.finished;
  s.refresh_archive_bytes = m.label_archive.bytes() + m.repair_archive.bytes() + m.frame_archive.bytes();
  s.external_poses = m.external_poses.value_or(false);
  s.segmenter = m.segmenter ? m.segmenter->name() : "none";
  return s;
}

std::vector<FrameResult> Mapper::frame_results() const {
  std::lock_guard lock(impl_->log_mutex);
  return impl_->frame_results;
}

std::map<std::string, TimingSummary> Mapper::timings() const {
  std::map<std::string, TimingSummary> out;
  for (const std::string& stage : impl_->timings.stages()) out[stage] = impl_->timings.summary(stage);
  return out;
}

void Mapper::add_timing(const std::string& stage, double ms) { impl_->timings.add(stage, ms); }
void Mapper::add_timing(const std::string& stage, const StageStart& start, std::optional<size_t> frame_index) {
  impl_->timings.add(stage, start, frame_index);
}

std::map<std::string, std::vector<StageSample>> Mapper::stage_samples() const {
  std::map<std::string, std::vector<StageSample>> out;
  for (const std::string& stage : impl_->timings.stages()) out[stage] = impl_->timings.samples(stage);
  return out;
}

const SemapConfig& Mapper::config() const { return impl_->config; }
const CameraModel& Mapper::camera() const { return impl_->camera; }

ArchiveSections Mapper::Impl::sections() const {
  ArchiveSections out;
  {
    std::lock_guard lock(tsdf_mutex);
    out[kTsdfSection] = encode_tsdf_section(tsdf.map());
  }
  {
    std::lock_guard lock(objects_mutex);
    out[kObjectsSection] = objects.encode_state();
    out[kObjectViewsSection] = objects.encode_views();  // the report's thumbnails (issue 43)
  }
  {
    std::lock_guard lock(tracker_mutex);
    if (tracker) out[kTrackingSection] = encode_tracker_state(tracker->state());
  }
  out[kCameraSection] = encode_camera_section(camera);
  out[kConfigSection] = config_yaml;
  return out;
}

void Mapper::Impl::restore(const ArchiveSections& saved, const std::filesystem::path& path) {
  saved_tsdf = archive_section(saved, kTsdfSection, path);
  saved_path = path;
  tsdf = SemanticTsdf(decode_tsdf_section(saved_tsdf, path, config.tsdf));
  objects.restore_state(archive_section(saved, kObjectsSection, path), path);
  if (const auto views = saved.find(kObjectViewsSection); views != saved.end())  // none before issue 43
    objects.restore_views(views->second, path);
  objects_in_map = objects.instances().size();
  external_poses = saved.count(kTrackingSection) == 0;  // no keyframes: only given poses can continue it
  if (*external_poses) return;
  make_tracker();
  tracker->resume(decode_tracker_state(saved.at(kTrackingSection), path));
}

SemanticTsdf Mapper::Impl::refresh_start() const {
  if (saved_tsdf.empty()) return SemanticTsdf(config.tsdf);
  return SemanticTsdf(decode_tsdf_section(saved_tsdf, saved_path, config.tsdf));
}

void Mapper::save(const std::filesystem::path& path) const { write_map_archive(path, impl_->sections()); }
void Mapper::save(const std::filesystem::path& path, const std::map<std::string, std::string>& extra_sections) const {
  ArchiveSections sections = impl_->sections();
  sections.insert(extra_sections.begin(), extra_sections.end());
  write_map_archive(path, sections);
}

std::unique_ptr<Mapper> Mapper::load(const std::filesystem::path& path, std::optional<SemapConfig> config,
                                     std::unique_ptr<Segmenter> segmenter) {
  const ArchiveSections saved = read_map_archive(path);
  const std::string& saved_yaml = archive_section(saved, kConfigSection, path);
  const SemapConfig saved_config = decode_config_section(saved_yaml, path);
  const CameraModel camera = decode_camera_section(archive_section(saved, kCameraSection, path), path);
  if (config) {
    require_same_ferns(saved_config.tracking, config->tracking, path);
    const int tsdf_threads = config->tsdf.threads;  // a run-time setting
    config->tsdf = saved_config.tsdf;  // the saved voxels and object points are made with these
    config->tsdf.threads = tsdf_threads;
    config->objects = saved_config.objects;
  }
  auto mapper = std::make_unique<Mapper>(config.value_or(saved_config), camera, std::move(segmenter));
  if (!config) mapper->impl_->config_yaml = saved_yaml;
  mapper->impl_->restore(saved, path);
  return mapper;
}

}  // namespace semap
