#include "semap/pipeline/run_pipeline.hpp"

#include "core/camera_difference.hpp"
#include "pipeline/map_archive.hpp"

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "semap/core/error.hpp"
#include "core/cpu_time.hpp"
#include "core/paths.hpp"
#include "core/progress.hpp"
#include "semap/eval/consistency_metrics.hpp"
#include "semap/io/dataset.hpp"
#include "semap/io/frame_source.hpp"
#include "io/output_folder.hpp"
#include "pipeline/bounded_queue.hpp"
#include "pipeline/report.hpp"
#include "pipeline/simulated_segmenter.hpp"
#include "semap/segmentation/segmenter_factory.hpp"

namespace semap {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// A frame as read from the source; nullopt when it was unreadable (skipped).
struct LoadedFrame {
  std::optional<Frame> frame;
};

/// Pulls frames from the source in order, ahead of the consumer on its own thread (decoding
/// overlaps tracking), or on demand when not threaded. Stops after `limit` frames (0 = none).
class Prefetcher {
 public:
  Prefetcher(size_t limit, size_t capacity, bool threaded, std::function<std::optional<LoadedFrame>()> pull)
      : limit_(limit), pull_(std::move(pull)), queue_(capacity) {
    if (threaded)
      thread_ = std::thread([this] {
        while (auto loaded = pull_limited())
          if (!queue_.push(std::move(*loaded))) break;
        queue_.close();
      });
  }
  ~Prefetcher() {
    queue_.close();
    if (thread_.joinable()) thread_.join();
  }
  std::optional<LoadedFrame> next() { return thread_.joinable() ? queue_.pop() : pull_limited(); }

 private:
  std::optional<LoadedFrame> pull_limited() {
    if (limit_ > 0 && pulled_ >= limit_) return std::nullopt;
    ++pulled_;
    return pull_();
  }
  size_t limit_, pulled_ = 0;
  std::function<std::optional<LoadedFrame>()> pull_;
  BoundedQueue<LoadedFrame> queue_;
  std::thread thread_;
};


/// The next frame of the source, or nullopt inside for an unreadable one (warned, skipped);
/// nullopt at the end or when a stop was requested.
std::optional<LoadedFrame> pull_frame(FrameSource& source, Mapper& mapper, const std::function<bool()>& stop) {
  if (stop && stop()) return std::nullopt;
  const StageStart t0 = StageStart::now();
  try {
    std::optional<Frame> frame = source.next();
    if (!frame) return std::nullopt;
    mapper.add_timing("read", t0, frame->index);
    return LoadedFrame{std::move(frame)};
  } catch (const Error& e) {
    spdlog::warn("skipping a frame: {}", e.what());
    return LoadedFrame{};
  }
}

/// RunOptions::realtime: holds each frame until the wall time since the first frame reaches its
/// recorded time since the first frame (timestamps that do not increase give no wait). Waits in
/// short slices so that a stop request (Ctrl-C) is not delayed.
class RecordedPace {
 public:
  explicit RecordedPace(const std::function<bool()>& stop) : stop_(stop) {}
  void wait_for(double timestamp_s) {
    if (!first_) first_ = std::pair{timestamp_s, Clock::now()};
    const auto due = first_->second + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double>(std::max(0.0, timestamp_s - first_->first)));
    while (Clock::now() < due && !(stop_ && stop_()))
      std::this_thread::sleep_for(std::min<Clock::duration>(due - Clock::now(), std::chrono::milliseconds(50)));
  }

 private:
  const std::function<bool()>& stop_;
  std::optional<std::pair<double, Clock::time_point>> first_;
};

/// Hints for a frame: the ground-truth pose when the run uses them (nullopt: skip the frame).
std::optional<FrameHints> hints_for(const Frame& frame, PoseSource poses) {
  FrameHints hints;
  if (poses == PoseSource::track) return hints;
  if (!frame.gt_T_world_camera || !is_valid_pose(*frame.gt_T_world_camera, 1e-4)) {
    spdlog::warn("skipping frame {}: no valid ground-truth pose", frame.index);
    return std::nullopt;
  }
  hints.T_world_camera = frame.gt_T_world_camera;
  return hints;
}

/// Feeds every usable frame to the mapper; returns (frames fed, frames skipped).
std::pair<size_t, size_t> feed_frames(Mapper& mapper, FrameSource& source, const RunOptions& options) {
  const SemapConfig& config = mapper.config();
  const size_t total = options.max_frames > 0 && source.size_hint() > 0 ? std::min(options.max_frames, source.size_hint())
                                                                          : std::max(options.max_frames, source.size_hint());
  Prefetcher frames(options.max_frames, static_cast<size_t>(config.pipeline.queue_size), config.pipeline.threads > 1,
                    [&] { return pull_frame(source, mapper, options.stop_requested); });
  Progress progress("semap run", total);
  size_t fed = 0, skipped = 0, objects = 0;
  RecordedPace pace(options.stop_requested);
  while (auto loaded = frames.next()) {
    const auto hints = loaded->frame ? hints_for(*loaded->frame, options.poses) : std::nullopt;
    if (hints) {
      if (options.realtime) pace.wait_for(loaded->frame->timestamp);
      mapper.add_frame(*loaded->frame, *hints);
      ++fed;
    } else {
      ++skipped;
    }
    if (!options.show_progress) continue;
    if ((fed + skipped) % 10 == 0) objects = mapper.stats().objects;
    progress.update(fed + skipped, "objects " + std::to_string(objects));
  }
  if (options.show_progress) progress.finish("objects " + std::to_string(mapper.stats().objects));
  return {fed, skipped};
}

/// Refuses to publish a run that mapped nothing useful (issue 22: no silent empty outputs).
void check_run_is_usable(const std::string& input, const MapperStats& stats, const MapOutputs& outputs,
                         size_t skipped) {
  if (stats.frames == 0)
    throw Error(input, "no frame could be used: all " + std::to_string(skipped) +
                           " were unreadable or without a valid pose (see the warnings above)");
  if (stats.segmented_frames > 0 && stats.segmentations_failed == stats.segmented_frames)
    throw Error(input, "every segmentation failed (" + stats.segmentation_error + ")");
  if (outputs.mesh.vertices.empty())
    throw Error(input, "the map is empty: no frame had valid depth within tsdf.min_depth..max_depth");
}

/// A resumed run whose every frame was held: it never relocalised into the saved map.
bool never_relocalised(const MapperStats& stats) {
  return stats.resumed_keyframes > 0 && stats.frames > 0 && stats.held_frames == stats.frames;
}

}  // namespace

// ---- default segmentation models (issue 38) ----

// The one translation unit that knows the install prefix and the source tree (compile
// definitions from src/pipeline/CMakeLists.txt): nothing else bakes in absolute paths.
std::vector<std::filesystem::path> model_search_path(const std::filesystem::path& option) {
  std::vector<std::filesystem::path> dirs;
  if (!option.empty()) dirs.push_back(option);
  if (const char* env = std::getenv("SEMAP_MODELS_DIR"); env && *env) dirs.emplace_back(env);
#ifdef SEMAP_INSTALL_DATADIR
  dirs.push_back(std::filesystem::path(SEMAP_INSTALL_DATADIR) / "semap" / "models");
#endif
#ifdef SEMAP_SOURCE_DIR
  dirs.push_back(std::filesystem::path(SEMAP_SOURCE_DIR).parent_path() / "shared" / "models");
#endif
  return dirs;
}

DefaultSegmenter find_default_segmenter(const std::vector<std::filesystem::path>& search_path) {
  for (const std::filesystem::path& dir : search_path) {
    const std::filesystem::path semantic = dir / kDefaultSemanticModel;
    std::filesystem::path instance;
    for (const char* name : kDefaultInstanceModels)
      if (instance.empty() && is_regular_file_path(dir / name)) instance = dir / name;
    const bool has_semantic = is_regular_file_path(semantic);
    if (has_semantic && !instance.empty())
      return {"panoptic:" + semantic.string() + "+" + instance.string(), dir};
    if (has_semantic) return {"semantic:" + semantic.string(), dir};
    if (!instance.empty()) return {"yolo:" + instance.string(), dir};
  }
  return {};
}

std::string run_segmenter_spec(const RunOptions& options, const SemapConfig& config,
                               std::filesystem::path* default_models_dir) {
  const std::string spec = options.segmenter.empty() ? config.segmentation.segmenter : options.segmenter;
  if (spec != kDefaultSegmenterSpec) return spec;
  const DefaultSegmenter found = find_default_segmenter(model_search_path(options.models_dir));
  if (!options.models_dir.empty() && found.dir != options.models_dir)
    throw Error(options.models_dir, std::string("--models: holds none of the default models (") +
                                        kDefaultSemanticModel + ", " + kDefaultInstanceModels[0] + ", " +
                                        kDefaultInstanceModels[1] + ")");
  if (default_models_dir) *default_models_dir = found.dir;
  return found.spec.empty() ? "none" : found.spec;
}

namespace {

std::unique_ptr<Segmenter> run_segmenter_from_spec(const std::string& spec, const RunOptions& options,
                                                   const SemapConfig& config, const FrameSource& source) {
  const bool simulated = options.seg_noise > 0;
  if ((spec == "groundtruth" || simulated) && !(source.dataset() && source.dataset()->has_label_ground_truth()))
    throw Error(source.name(), "--segmenter groundtruth / --seg-noise need per-frame label images, this input has none");
  if (!simulated) return make_segmenter(spec, config.segmentation, source.camera());
  SegmentationNoiseParams noise = config.simulated_segmentation;
  noise.flicker_rate = options.seg_noise;
  return std::make_unique<SimulatedSegmenter>(make_segmenter("groundtruth", config.segmentation, source.camera()),
                                              noise, 1);
}

}  // namespace

std::unique_ptr<Segmenter> make_run_segmenter(const RunOptions& options, const SemapConfig& config,
                                              const FrameSource& source) {
  return run_segmenter_from_spec(run_segmenter_spec(options, config), options, config, source);
}

namespace {

/// The configuration the Mapper runs with: a live camera never makes tracking wait for the
/// network (METHODS C1 runs on what it can); the segmenter is built by the driver, once.
SemapConfig mapper_config_for(const SemapConfig& config, const FrameSource& source) {
  SemapConfig c = config;
  c.segmentation.segmenter = "none";
  if (source.is_live()) c.segmentation.when_busy = WhenBusy::drop_oldest;
  return c;
}

/// The saved map a run continues (RunOptions::resume_from): a folder's map.semap, or the file.
std::filesystem::path saved_map_path(const RunOptions& options) {
  // --out being (or holding) the saved map is refused by the OutputFolder (its inputs).
  const std::filesystem::path path = map_file_of(options.resume_from);
  if (options.poses == PoseSource::groundtruth)
    throw Error(path, "--resume relocalises the recording into the saved map: it needs --poses track");
  return path;
}

std::unique_ptr<Mapper> make_run_mapper(const RunOptions& options, const SemapConfig& config, const FrameSource& source,
                                        std::unique_ptr<Segmenter> segmenter) {
  const SemapConfig mapper_config = mapper_config_for(config, source);
  if (options.resume_from.empty()) return std::make_unique<Mapper>(mapper_config, source.camera(), std::move(segmenter));
  const std::filesystem::path path = saved_map_path(options);
  auto mapper = Mapper::load(path, mapper_config, std::move(segmenter));
  const PinholeIntrinsics &saved = mapper->camera().depth, &given = source.camera().depth;
  if (!(saved == given))
    throw Error(options.dataset, "its depth camera is not the one of the saved map " + path.string() + " (" +
                                     describe_camera_difference(given, saved) + ")");
  if (options.show_progress)
    std::fprintf(stderr,
                 "semap run: continuing %s (%zu keyframes, %zu objects, its %g m voxels): relocalising the first frames into it\n",
                 path.string().c_str(), mapper->stats().resumed_keyframes, mapper->stats().objects,
                 mapper->config().tsdf.voxel_size);
  return mapper;
}

/// finish() re-reads frames of a dataset for the map refresh (only the depth image when the
/// colour is not needed); cameras and recordings rely on the Mapper's own archive.
void set_reloader(Mapper& mapper, const DatasetReader* dataset) {
  if (!dataset) return;
  mapper.set_frame_reloader([dataset](size_t i, bool need_colour) {
    if (need_colour) return dataset->load(i);
    Frame frame;
    frame.index = i;
    frame.depth = dataset->load_depth(i);
    return frame;
  });
}

/// Shows the Mapper to RunOptions::observe_mapper for the scope's lifetime.
class ObserverScope {
 public:
  ObserverScope(const std::function<void(const Mapper*)>& observe, const Mapper& mapper) : observe_(observe) {
    if (observe_) observe_(&mapper);
  }
  ~ObserverScope() {
    if (observe_) observe_(nullptr);
  }
  ObserverScope(const ObserverScope&) = delete;
  ObserverScope& operator=(const ObserverScope&) = delete;

 private:
  const std::function<void(const Mapper*)>& observe_;
};

}  // namespace

/// A source mapped to the end (pose graph, map refresh, final object pass).
struct MappedSource {
  std::unique_ptr<Mapper> mapper;
  size_t fed = 0, skipped = 0;
  bool stopped_early = false;
  bool not_merged = false;  ///< --resume given, but the recording never relocalised into the saved map
  Clock::time_point reading_ended;  ///< the streaming stages' end (fps online), before finish()
  double cpu_ms_reading_ended = 0;  ///< process CPU then
  double opencv_workers_ms_reading_ended = 0;  ///< of OpenCV's workers then
  std::filesystem::path default_models_dir;  ///< where the default models came from (RunResult)
};

MappedSource map_source(const RunOptions& options, const SemapConfig& config, FrameSource& source) {
  MappedSource out;
  const std::string spec = run_segmenter_spec(options, config, &out.default_models_dir);
  std::unique_ptr<Segmenter> segmenter = run_segmenter_from_spec(spec, options, config, source);
  const bool wanted_default = (options.segmenter.empty() ? config.segmentation.segmenter : options.segmenter) ==
                              kDefaultSegmenterSpec;
  if (!segmenter && options.show_progress && wanted_default) {
    std::string searched;
    for (const auto& dir : model_search_path(options.models_dir)) searched += (searched.empty() ? "" : ", ") + dir.string();
    std::fprintf(stderr, "semap run: no segmentation models in %s: mapping geometry and colour only (--models DIR)\n",
                 searched.c_str());
  } else if (!segmenter && options.show_progress)
    std::fprintf(stderr, "semap run: no segmenter: mapping geometry and colour only (add --segmenter "
                         "yolo:MODEL.onnx for classes and objects)\n");
  else if (wanted_default && options.show_progress)
    std::fprintf(stderr, "semap run: default segmentation models from %s\n", out.default_models_dir.string().c_str());
  out.mapper = make_run_mapper(options, config, source, std::move(segmenter));
  set_reloader(*out.mapper, source.dataset());
  const ObserverScope observed(options.observe_mapper, *out.mapper);
  std::tie(out.fed, out.skipped) = feed_frames(*out.mapper, source, options);
  // Asked once, when reading ended: a request during the final pass did not cut the input short.
  out.stopped_early = options.stop_requested && options.stop_requested();
  // Ctrl-C before any frame was mapped: there is no map to finish; publish nothing.
  if (out.fed == 0 && out.stopped_early) throw_if_interrupted();
  out.reading_ended = Clock::now();
  out.cpu_ms_reading_ended = process_cpu_ms();
  out.opencv_workers_ms_reading_ended = opencv_workers_cpu_ms();
  out.mapper->finish();
  if (out.mapper->stats().resumed_keyframes > 0 && options.show_progress && !never_relocalised(out.mapper->stats()))
    std::fprintf(stderr, "semap run: relocalised into the saved map after %zu held frames\n",
                 out.mapper->stats().held_frames);
  return out;
}

RunResult run_pipeline(const RunOptions& options, const SemapConfig& config) {
  config.validate();
  const auto wall_start = Clock::now();
  const double cpu_start_ms = process_cpu_ms(), opencv_workers_start_ms = opencv_workers_cpu_ms();
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, config.pipeline.threads);
  const auto source = open_frame_source(options.dataset.string(), options.dataset_options);
  // Opened before mapping: a folder that cannot take outputs fails now, not after the work.
  // Never the dataset or the map to resume, nor a folder holding one (issue 44).
  std::vector<std::filesystem::path> inputs = {options.resume_from};
  if (!options.dataset_inside_out_dir) inputs.push_back(options.dataset);
  // The models and precomputed:DIR the segmenter reads (the option's spec or the config's).
  for (const auto& path : segmenter_input_paths(options.segmenter.empty() ? config.segmentation.segmenter : options.segmenter))
    inputs.push_back(path);
  OutputFolder out(options.out_dir, {.tool = "run", .publish_last = {"report.html", "report.json"}, .inputs = inputs,
                                     .planned = map_output_files()});
  const DatasetReader* dataset = source->dataset();
  if (dataset && dataset->size() == 0) throw Error(options.dataset, "dataset has no frames");
  if (!enum_value(kRunPoseSourceNames, enum_name(kPoseSourceNames, options.poses)))
    throw Error(options.dataset, "semap run takes poses from tracking or the ground truth, not '" +
                                     std::string(enum_name(kPoseSourceNames, options.poses)) + "'");
  const bool poses_given = options.poses == PoseSource::groundtruth;
  if (poses_given && !(dataset && dataset->has_ground_truth()))
    throw Error(options.dataset, "--poses groundtruth needs a ground-truth trajectory, this input has none");

  MappedSource mapped = map_source(options, config, *source);
  if (never_relocalised(mapped.mapper->stats()) && dataset && !mapped.stopped_early) {
    // Issue 19: not merged at a guessed pose; the recording becomes a map of its own.
    std::fprintf(stderr, "semap run: %s: no frame relocalised into the saved map %s (%zu keyframes tried): "
                         "mapping this recording on its own, not merged\n",
                 source->name().c_str(), options.resume_from.string().c_str(), mapped.mapper->stats().resumed_keyframes);
    RunOptions alone = options;
    alone.resume_from.clear();
    mapped = map_source(alone, config, *open_frame_source(options.dataset.string(), options.dataset_options));
    mapped.not_merged = true;
  }
  const size_t fed = mapped.fed, skipped = mapped.skipped;
  const bool stopped_early = mapped.stopped_early;
  const double online_s = std::chrono::duration<double>(mapped.reading_ended - wall_start).count();
  Mapper& mapper = *mapped.mapper;
  const MapOutputs outputs = collect_outputs(mapper);
  RunResult result;
  result.mapper = mapper.stats();
  result.not_merged = mapped.not_merged;
  result.default_models_dir = mapped.default_models_dir;
  check_run_is_usable(source->name(), result.mapper, outputs, skipped);

  write_map_outputs(mapper, outputs, out.staging());
  if (options.evaluate && dataset) result.evaluation = evaluate_run(*dataset, outputs, poses_given);
  result.dataset = source->name();
  result.poses = options.poses;
  result.frames_read = fed;
  result.frames_skipped = skipped;
  result.mesh_vertices = outputs.mesh.vertices.size();
  result.mesh_triangles = outputs.mesh.triangles.size();
  result.objects_per_class = objects_per_class(outputs.objects);
  result.threads = config.pipeline.threads;
  result.timings = mapper.timings();
  result.frames = mapper.frame_results();
  result.stage_samples = mapper.stage_samples();
  result.fps_online = static_cast<double>(fed + skipped) / std::max(online_s, 1e-9);
  result.cpu_s_online = (mapped.cpu_ms_reading_ended - cpu_start_ms) * 1e-3;
  result.cpu_s_online_opencv_workers = (mapped.opencv_workers_ms_reading_ended - opencv_workers_start_ms) * 1e-3;
  result.wall_s = seconds_since(wall_start);
  result.fps_end_to_end = static_cast<double>(fed + skipped) / std::max(result.wall_s, 1e-9);
  result.peak_rss_mb = static_cast<double>(peak_rss_bytes()) / (1024.0 * 1024.0);
  result.stopped_early = stopped_early;
  write_run_report(out.staging(), result, outputs);
  out.publish();
  return result;
}

nlohmann::json to_json(const RunResult& r) {
  const MapperStats& m = r.mapper;
  nlohmann::json report;
  report["dataset"] = r.dataset;
  report["summary"] = {
      {"frames", r.frames_read + r.frames_skipped},
      {"frames_skipped", r.frames_skipped},
      {"frames_lost", m.lost_frames},
      {"keyframes", m.keyframes},
      {"segmented_frames", m.segmented_frames},
      {"semantic_segmented_frames", m.semantic_segmented_frames},
      {"segmentations_dropped", m.segmentations_dropped},
      {"segmentations_failed", m.segmentations_failed},
      {"object_frames", m.object_frames},
      {"object_accumulations_skipped", m.object_accumulations_skipped},
      {"objects", m.objects},
      {"objects_created", m.objects_created},  // C4, then removed by C5's delete and merge steps
      {"objects_deleted", m.objects_deleted},
      {"objects_merged", m.objects_merged},
      {"poses", std::string(enum_name(kPoseSourceNames, r.poses))},
      {"segmenter", m.segmenter},
      {"loop_edges", m.loop_edges},
      {"map_refreshed_with_optimised_poses", m.map_refreshed},
      {"max_pose_correction_m", m.max_pose_correction_m},
      {"refresh_archive_mb", static_cast<double>(m.refresh_archive_bytes) / (1024.0 * 1024.0)},
      {"mesh_vertices", r.mesh_vertices},
      {"mesh_triangles", r.mesh_triangles},
      {"fps_online", r.driver_measured ? nlohmann::json(r.fps_online) : nlohmann::json(nullptr)},
      {"fps_end_to_end", r.driver_measured ? nlohmann::json(r.fps_end_to_end) : nlohmann::json(nullptr)},
      {"cpu_s_online", r.driver_measured ? nlohmann::json(r.cpu_s_online) : nlohmann::json(nullptr)},
      {"cpu_s_online_opencv_workers",
       r.driver_measured ? nlohmann::json(r.cpu_s_online_opencv_workers) : nlohmann::json(nullptr)},
      {"wall_s", r.driver_measured ? nlohmann::json(r.wall_s) : nlohmann::json(nullptr)},
      {"driver", r.driver_measured ? "semap run" : "library (write_map_outputs)"},
      {"peak_rss_mb", r.peak_rss_mb},
      {"threads", r.threads},
  };
  if (!m.map_refresh_note.empty()) report["summary"]["map_refresh_note"] = m.map_refresh_note;
  if (r.stopped_early) report["summary"]["stopped_early"] = true;
  if (!r.default_models_dir.empty()) report["summary"]["default_models_dir"] = r.default_models_dir.string();
  report["objects_per_class"] = r.objects_per_class;
  report["evaluation"] = to_json(r.evaluation);
  report["timings"] = timings_json(r.timings);
  report["frames"] = frames_json(r.frames, r.stage_samples, r.evaluation.ate);
  if (!m.external_poses)
    report["tracking"] = {{"keyframes", m.keyframes}, {"lost_frames", m.lost_frames},
                          {"relocalisations", m.relocalisations}, {"loop_edges", m.loop_edges},
                          {"optimisations", m.optimisations},
                          {"checks", {{"verified", m.verified_registrations}, {"dense_residual_failed", m.dense_residual_failed},
                                      {"spread_failed", m.spread_failed}, {"ambiguous", m.ambiguous_matches},
                                      {"under_constrained", m.under_constrained}}}};
  if (m.resumed_keyframes > 0)  // issue 19: how this recording joined the saved map
    report["resumed"] = {{"saved_keyframes", m.resumed_keyframes}, {"held_frames", m.held_frames}};
  if (r.not_merged) report["resumed"] = {{"merged", false}, {"why", "no frame relocalised into the saved map"}};
  return report;
}

}  // namespace semap
