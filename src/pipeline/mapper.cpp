#include "pipeline/mapper.hpp"

#include <spdlog/spdlog.h>
#include <tbb/global_control.h>
#include <tbb/parallel_pipeline.h>

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <thread>
#include <unordered_map>

#include "core/error.hpp"
#include "core/paths.hpp"
#include "core/progress.hpp"
#include "eval/object_metrics.hpp"
#include "eval/semantic_metrics.hpp"
#include "eval/trajectory_metrics.hpp"
#include "io/dataset.hpp"
#include "io/ply_io.hpp"
#include "io/trajectory_io.hpp"
#include "objects/object_mapper.hpp"
#include "pipeline/bounded_queue.hpp"
#include "pipeline/refresh_archive.hpp"
#include "pipeline/report.hpp"
#include "pipeline/simulated_segmenter.hpp"
#include "pipeline/stage_timer.hpp"
#include "segmentation/segmenter_factory.hpp"
#include "segmentation/temporal_filter.hpp"
#include "tracking/depth_repair.hpp"
#include "tracking/tracker.hpp"
#include "tsdf/semantic_tsdf.hpp"

namespace semap {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

/// A tracked frame on its way to fusion.
struct TrackedFrame {
  Frame frame;                 ///< depth is the repaired depth used for tracking
  Pose T_world_camera;
  bool segment = false;        ///< sent to the segmenter; fusion waits for its labels
  bool map_objects = false;    ///< its segmentation also feeds the object map
};

/// A frame as read from the dataset; nullopt when it was unreadable (skipped).
struct LoadedFrame {
  size_t index = 0;
  std::optional<Frame> frame;
};

/// Joins the stage threads when the pipeline scope ends, normally or by an exception
/// (after on_exit has closed the queues the threads wait on).
struct StageThreads {
  std::vector<std::thread> threads;
  std::function<void()> on_exit;
  void join_all() {
    for (std::thread& t : threads)
      if (t.joinable()) t.join();
  }
  ~StageThreads() {
    if (on_exit) on_exit();
    join_all();
  }
};

/// What fusion hands to the object map.
struct ObjectWork {
  Frame frame;
  SegmentationResult segmentation;
  Pose T_world_camera;
  bool keyframe = true;  ///< false: a segmented frame between object keyframes (ObjectMapper::accumulate)
};

/// Results of the asynchronous segmentation stage, keyed by the frame they were computed on.
class SegmentationResults {
 public:
  void put(size_t frame_index, std::optional<SegmentationResult> result) {
    std::lock_guard lock(mutex_);
    results_[frame_index] = std::move(result);
    ready_.notify_all();
  }
  /// The result for frame_index if it has arrived (nullopt inside means "dropped / failed").
  std::optional<std::optional<SegmentationResult>> take(size_t frame_index) {
    std::lock_guard lock(mutex_);
    auto it = results_.find(frame_index);
    if (it == results_.end()) return std::nullopt;
    auto out = std::move(it->second);
    results_.erase(it);
    return out;
  }
  std::optional<SegmentationResult> wait_take(size_t frame_index) {
    std::unique_lock lock(mutex_);
    ready_.wait(lock, [&] { return results_.count(frame_index) > 0; });
    auto out = std::move(results_[frame_index]);
    results_.erase(frame_index);
    return out;
  }

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::map<size_t, std::optional<SegmentationResult>> results_;
};

std::unique_ptr<Segmenter> build_segmenter(const RunOptions& options, const SemapConfig& config,
                                           const DatasetReader& dataset) {
  const std::string spec = options.segmenter.empty() ? config.segmentation.segmenter : options.segmenter;
  const bool simulated = options.seg_noise > 0;
  if ((spec == "groundtruth" || simulated) && !dataset.has_label_ground_truth())
    throw Error(dataset.root(), "--segmenter groundtruth / --seg-noise need per-frame label images, this dataset has none");
  if (simulated) {
    SegmentationNoiseParams noise = config.simulated_segmentation;
    noise.flicker_rate = options.seg_noise;
    return std::make_unique<SimulatedSegmenter>(make_segmenter("groundtruth", config.segmentation, dataset.camera()),
                                                noise, 1);
  }
  return make_segmenter(spec, config.segmentation, dataset.camera());
}

/// Ground-truth poses when present, or nullopt.
std::optional<Pose> usable_pose(const std::optional<Pose>& pose) {
  if (pose && is_valid_pose(*pose, 1e-4)) return pose;
  return std::nullopt;
}

nlohmann::json objects_per_class(const ObjectMapper& objects) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& inst : objects.instances()) {
    const std::string name(class_name(inst.class_id()));
    j[name] = j.value(name, 0) + 1;
  }
  return j;
}

std::vector<ReportObject> report_objects(const nlohmann::json& objects_json) {
  std::vector<ReportObject> out;
  for (const auto& o : objects_json.value("objects", nlohmann::json::array())) {
    ReportObject r;
    r.id = o.value("id", 0u);
    r.class_id = static_cast<ClassId>(o.value("class_id", 0));
    const auto& obb = o["obb"];
    Eigen::Vector3d c(obb["center"][0], obb["center"][1], obb["center"][2]);
    Eigen::Vector3d e(obb["extent"][0], obb["extent"][1], obb["extent"][2]);
    Eigen::Matrix3d R;
    for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = obb["rotation"][i];
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d s((k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5);
      r.corners[k] = c + R * s.cwiseProduct(e);
    }
    out.push_back(r);
  }
  return out;
}

}  // namespace

nlohmann::json run_pipeline(const RunOptions& options, const SemapConfig& config) {
  config.validate();
  const auto wall_start = Clock::now();
  const int threads = config.pipeline.threads;
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, threads);
  const bool sequential = threads == 1;

  auto dataset = open_dataset(options.dataset);
  const CameraModel& camera = dataset->camera();
  const size_t frame_count =
      options.max_frames > 0 ? std::min(options.max_frames, dataset->size()) : dataset->size();
  if (frame_count == 0) throw Error(options.dataset, "dataset has no frames");
  const bool use_gt_poses = options.poses == "groundtruth";
  if (use_gt_poses && !dataset->has_ground_truth())
    throw Error(options.dataset, "--poses groundtruth needs a ground-truth trajectory, this dataset has none");

  std::error_code ec;
  std::filesystem::create_directories(options.out_dir, ec);
  if (ec) throw Error(options.out_dir, "cannot create output folder: " + ec.message());

  std::unique_ptr<Segmenter> segmenter = build_segmenter(options, config, *dataset);
  // Ground-truth / simulated / precomputed labels cost nothing: label every frame for the
  // TSDF; the object map still takes every N-th frame and keyframes (its C2 step is the cost).
  const std::string spec = options.segmenter.empty() ? config.segmentation.segmenter : options.segmenter;
  const bool label_every_frame = segmenter && (options.seg_noise > 0 || spec == "groundtruth" || spec.rfind("precomputed:", 0) == 0);
  std::unique_ptr<Tracker> tracker = use_gt_poses ? nullptr : std::make_unique<Tracker>(config.tracking, camera);
  SemanticTsdf tsdf(config.tsdf);
  ObjectMapper objects(config.objects, camera);
  StageTimings timings;
  LabelArchive label_archive;
  // Only a tracked run refreshes the map; with a colour layer it needs the colour images anyway.
  RepairArchive repair_archive(camera.depth_scale, tracker && !config.tsdf.colour_layer
                                                       ? static_cast<size_t>(config.pipeline.refresh_cache_mb) << 20
                                                       : 0);
  SegmentationResults seg_results;
  // METHODS.md B1: the temporal label filter sits between segmentation and the TSDF. It sees
  // the labelled frames in frame order (fusion is the only caller). The object map gets the
  // unfiltered masks: dropping border pixels there only shrinks instances (C2 does its own
  // consistency through association counts, C5).
  TemporalLabelFilter temporal_filter(config.segmentation.temporal, camera.depth);
  const DepthRepairParams repair{config.tracking.depth_repair_radius, config.tracking.depth_repair_gray_threshold,
                                 config.tracking.depth_repair_min_support};

  std::atomic<size_t> frames_done{0}, skipped_frames{0}, segmented_frames{0}, dropped_segmentations{0};
  std::atomic<size_t> keyframes{0}, objects_processed{0}, objects_in_map{0}, skipped_accumulations{0};
  Trajectory online_trajectory;
  std::vector<size_t> online_frame_indices;  // frame of each online_trajectory entry

  // --- stage bodies -------------------------------------------------------------------
  auto run_segmentation = [&](const Frame& frame) -> std::optional<SegmentationResult> {
    const auto t0 = Clock::now();
    try {
      SegmentationResult r = segmenter->segment(frame);
      r.frame_index = frame.index;
      timings.add("segmentation", ms_since(t0));
      return r;
    } catch (const Error& e) {
      spdlog::warn("segmentation of frame {} failed: {}", frame.index, e.what());
      return std::nullopt;
    }
  };
  auto fuse = [&](TrackedFrame& item, const std::optional<SegmentationResult>& seg) {
    const auto t0 = Clock::now();
    IntegrationInput input = make_integration_input(item.frame, camera.depth, item.T_world_camera);
    input.labels = cv::Mat();
    if (seg && seg->has_labels()) {
      input.labels = temporal_filter.apply(seg->labels, item.frame.depth, item.T_world_camera);
      input.confidence = seg->confidence;
      input.probabilities = seg->probabilities;
      if (tracker) label_archive.store(item.frame.index, input.labels);  // only a tracked run refreshes
    }
    tsdf.integrate(input);
    timings.add("tsdf_integration", ms_since(t0));
  };
  auto map_objects = [&](ObjectWork& work) {
    const auto t0 = Clock::now();
    if (!work.keyframe) {
      objects.accumulate(work.frame, work.segmentation, work.T_world_camera);
      timings.add("object_accumulate", ms_since(t0));
      return;
    }
    objects.process(work.frame, work.segmentation, work.T_world_camera);
    timings.add("object_map", ms_since(t0));
    ++objects_processed;
    objects_in_map = objects.instances().size();
  };

  // Reads frame i; nullopt (counted, warned) for an unreadable frame (issue 8).
  auto load_frame = [&](size_t i) -> std::optional<Frame> {
    const auto t0 = Clock::now();
    try {
      Frame frame = dataset->load(i);
      timings.add("read", ms_since(t0));
      return frame;
    } catch (const Error& e) {
      spdlog::warn("skipping frame {}: {}", i, e.what());
      ++skipped_frames;
      return std::nullopt;
    }
  };
  // Repairs and tracks a loaded frame. Returns nullopt for a skipped frame.
  auto track_frame = [&](Frame frame) -> std::optional<TrackedFrame> {
    const auto t0 = Clock::now();
    TrackedFrame item;
    if (use_gt_poses) {
      const auto pose = usable_pose(frame.gt_T_world_camera);
      if (!pose) {
        spdlog::warn("skipping frame {}: no valid ground-truth pose", frame.index);
        ++skipped_frames;
        return std::nullopt;
      }
      item.T_world_camera = *pose;
      if (config.tracking.depth_repair) frame.depth = repair_depth(frame.depth, frame.rgb, repair);
      timings.add("depth_repair", ms_since(t0));
    } else {
      const TrackResult r = tracker->track(frame);
      item.T_world_camera = r.T_world_camera;
      if (!r.depth.empty()) {
        repair_archive.store(frame.index, frame.depth, r.depth);
        frame.depth = r.depth;
      }
      if (r.is_keyframe) ++keyframes;
      timings.add("tracking", ms_since(t0));
      item.segment = r.is_keyframe && config.segmentation.on_keyframes;
    }
    online_trajectory.push_back({frame.timestamp, item.T_world_camera});
    online_frame_indices.push_back(frame.index);
    item.map_objects = segmenter && (item.segment || frame.index % config.segmentation.every_n_frames == 0);
    item.segment = item.map_objects || label_every_frame;
    item.frame = std::move(frame);
    return item;
  };

  Progress progress("semap run", frame_count);
  auto progress_extra = [&] { return "objects " + std::to_string(objects_in_map.load()); };

  if (sequential) {
    // One thread: the same order every time -> byte-identical outputs (issue 8).
    for (size_t i = 0; i < frame_count; ++i) {
      auto frame = load_frame(i);
      auto item = frame ? track_frame(std::move(*frame)) : std::nullopt;
      if (item) {
        std::optional<SegmentationResult> seg;
        if (item->segment) {
          seg = run_segmentation(item->frame);
          ++segmented_frames;
        }
        fuse(*item, seg);
        if (seg && (item->map_objects || objects.accumulates())) {
          ObjectWork work{std::move(item->frame), std::move(*seg), item->T_world_camera, item->map_objects};
          map_objects(work);
        }
      }
      frames_done = i + 1;
      if (options.show_progress) progress.update(i + 1, progress_extra());
    }
  } else {
    // Stages on their own threads joined by bounded queues. Tracking never waits for the
    // network: frames to segment go to a small queue and are dropped when it is full; fusion
    // holds such frames aside until their labels arrive and meanwhile fuses the others.
    BoundedQueue<TrackedFrame> fusion_queue(config.pipeline.queue_size);
    BoundedQueue<Frame> segmentation_queue(static_cast<size_t>(config.segmentation.async_queue_size));
    BoundedQueue<ObjectWork> object_queue(config.pipeline.queue_size);
    BoundedQueue<LoadedFrame> read_queue(config.pipeline.queue_size);
    std::atomic<size_t> segmentation_in_flight{0};
    // On an exception in the tracking loop every queue is closed and every stage joined, so
    // the error reaches the caller instead of std::terminate.
    StageThreads threads_guard;
    threads_guard.on_exit = [&] {
      read_queue.close();
      segmentation_queue.close();
      fusion_queue.close();
      object_queue.close();
    };

    threads_guard.threads.emplace_back([&] {
      while (auto frame = segmentation_queue.pop()) {
        seg_results.put(frame->index, run_segmentation(*frame));
        --segmentation_in_flight;
      }
    });
    threads_guard.threads.emplace_back([&] {
      while (auto work = object_queue.pop()) map_objects(*work);
    });
    threads_guard.threads.emplace_back([&] {
      std::map<size_t, TrackedFrame> waiting;  // frames held until their labels arrive
      auto fuse_ready = [&](bool block) {
        for (auto it = waiting.begin(); it != waiting.end();) {
          auto result = block ? std::optional(seg_results.wait_take(it->first)) : seg_results.take(it->first);
          if (!result) { ++it; continue; }
          fuse(it->second, *result);
          if (*result && it->second.map_objects) {
            object_queue.push({std::move(it->second.frame), std::move(**result), it->second.T_world_camera, true});
          } else if (*result && objects.accumulates()) {
            // Points between object keyframes are best effort: skipped when the object stage is busy.
            if (!object_queue.try_push({std::move(it->second.frame), std::move(**result), it->second.T_world_camera, false}))
              ++skipped_accumulations;
          }
          it = waiting.erase(it);
        }
      };
      while (auto item = fusion_queue.pop()) {
        if (item->segment) {
          waiting.emplace(item->frame.index, std::move(*item));
        } else {
          fuse(*item, std::nullopt);
        }
        fuse_ready(false);
      }
      fuse_ready(true);
      object_queue.close();
    });

    // Reading (PNG decoding) runs ahead of tracking on its own thread, in frame order.
    threads_guard.threads.emplace_back([&] {
      for (size_t i = 0; i < frame_count; ++i)
        if (!read_queue.push({i, load_frame(i)})) break;
      read_queue.close();
    });

    while (auto loaded = read_queue.pop()) {
      auto item = loaded->frame ? track_frame(std::move(*loaded->frame)) : std::nullopt;
      if (item) {
        if (item->segment) {
          // Non-blocking hand-off: drop the request when the network is still busy.
          if (segmentation_in_flight.load() < segmentation_queue.capacity()) {
            ++segmentation_in_flight;
            ++segmented_frames;
            segmentation_queue.push(item->frame);
          } else {
            item->segment = item->map_objects = false;
            ++dropped_segmentations;
          }
        }
        fusion_queue.push(std::move(*item));
      }
      frames_done = loaded->index + 1;
      if (options.show_progress) progress.update(frames_done, progress_extra());
    }
    segmentation_queue.close();
    fusion_queue.close();
    threads_guard.join_all();
  }
  const double online_s = std::chrono::duration<double>(Clock::now() - wall_start).count();

  // --- final pose-graph pass and map refresh -------------------------------------------
  Trajectory trajectory = online_trajectory;
  bool map_refreshed = false;
  TrackerStats tracker_stats;
  double max_pose_correction = 0.0;
  if (tracker) {
    const auto t0 = Clock::now();
    trajectory = tracker->finish();
    tracker_stats = tracker->stats();
    timings.add("pose_graph_final", ms_since(t0));
    // The map uses the optimised poses: when loop closure moved the frames by more than a
    // quarter voxel (at the far end of the depth range), the TSDF is rebuilt from every frame
    // with its optimised pose and the labels archived for segmented frames.
    auto pose_at = [&](double timestamp) -> std::optional<Pose> {
      const auto it = std::lower_bound(trajectory.begin(), trajectory.end(), timestamp - 1e-9,
                                       [](const StampedPose& p, double t) { return p.timestamp < t; });
      if (it == trajectory.end() || std::abs(it->timestamp - timestamp) > 1e-6) return std::nullopt;
      return it->T_world_camera;
    };
    // Per online frame, the correction T_optimised * T_online^-1 of the final pass, and how far
    // it moves a surface point at the far end of the depth range (camera shift + angle * range).
    std::unordered_map<uint32_t, Eigen::Isometry3f> corrections;
    for (size_t k = 0; k < online_trajectory.size(); ++k) {
      const auto optimised = pose_at(online_trajectory[k].timestamp);
      if (!optimised) continue;
      const Pose& online = online_trajectory[k].T_world_camera;
      const Pose correction = *optimised * online.inverse();
      corrections[static_cast<uint32_t>(online_frame_indices[k])] = correction.cast<float>();
      max_pose_correction = std::max(max_pose_correction, (optimised->translation() - online.translation()).norm() +
                                                              Eigen::AngleAxisd(correction.linear()).angle() *
                                                                  config.tsdf.max_range);
    }
    // Object points move with the frame they were observed in.
    if (tracker_stats.loop_edges > 0) objects.apply_pose_corrections(corrections);
    if (tracker_stats.loop_edges > 0 && max_pose_correction > 0.25 * config.tsdf.voxel_size) {
      const auto t1 = Clock::now();
      SemanticTsdf refreshed(config.tsdf);
      // Reading, repair and label decoding run in parallel; integration stays serial in frame
      // order, so one thread still gives byte-identical maps (issue 8).
      size_t next = 0;
      tbb::parallel_pipeline(
          static_cast<size_t>(2 * threads),
          tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                         [&](tbb::flow_control& fc) -> size_t {
                                           if (next >= frame_count) fc.stop();
                                           return next++;
                                         }) &
              tbb::make_filter<size_t, std::optional<IntegrationInput>>(
                  tbb::filter_mode::parallel,
                  [&](size_t i) -> std::optional<IntegrationInput> {
                    const auto pose = pose_at(dataset->records()[i].timestamp);
                    if (!pose) return std::nullopt;  // skipped in the online pass
                    Frame frame;
                    try {
                      if (repair_archive.has(i)) {  // depth image + the archived repair fills
                        frame.index = i;
                        frame.depth = dataset->load_depth(i);
                        repair_archive.apply(i, frame.depth);
                      } else {
                        frame = dataset->load(i);
                        if (config.tracking.depth_repair) frame.depth = repair_depth(frame.depth, frame.rgb, repair);
                      }
                    } catch (const Error&) {
                      return std::nullopt;  // warned and counted in the online pass
                    }
                    IntegrationInput input = make_integration_input(frame, camera.depth, *pose);  // shares the images
                    input.labels = label_archive.find(frame.index);
                    return input;
                  }) &
              tbb::make_filter<std::optional<IntegrationInput>, void>(
                  tbb::filter_mode::serial_in_order,
                  [&](const std::optional<IntegrationInput>& input) {
                    if (input) refreshed.integrate(*input);
                  }));
      tsdf = std::move(refreshed);
      map_refreshed = true;
      timings.add("map_refresh", ms_since(t1));
    }
  }
  {
    const auto t0 = Clock::now();
    objects.finish();
    timings.add("object_map_final", ms_since(t0));
  }

  // --- outputs ----------------------------------------------------------------------
  const auto t_out = Clock::now();
  write_tum_trajectory(options.out_dir / "trajectory.txt", trajectory);
  TriangleMesh mesh = tsdf.extract_mesh();
  timings.add("mesh_extraction", ms_since(t_out));
  mesh.vertices.instances =
      objects.instance_ids_for(mesh.vertices.points, static_cast<float>(1.5 * config.tsdf.voxel_size));
  write_ply(options.out_dir / "mesh.ply", mesh);
  tsdf.save(options.out_dir / "map.semap");
  objects.write(options.out_dir);
  const nlohmann::json objects_json = objects.to_json();

  // --- evaluation against ground truth -----------------------------------------------
  // The map lives in the tracker's world (first camera); for evaluation it is moved into the
  // ground-truth world by the ATE alignment (Horn/Umeyama), as the TUM benchmark aligns.
  nlohmann::json evaluation = nlohmann::json::object();
  if (options.evaluate) {
    Pose T_gt_map = Pose::Identity();
    if (!use_gt_poses && dataset->has_ground_truth()) {
      try {
        const Trajectory gt = dataset->ground_truth();
        const AteResult ate = compute_ate(gt, trajectory);
        T_gt_map = ate.T_gt_est;
        evaluation["ate"] = to_json(ate);
        evaluation["rpe"] = to_json(compute_rpe(gt, trajectory));
      } catch (const Error& e) {
        spdlog::warn("trajectory evaluation skipped: {}", e.what());
      }
    }
    const Eigen::Affine3f T = T_gt_map.cast<float>();
    const auto gt_points = dataset->root() / "gt_points.ply";
    if (std::filesystem::exists(gt_points)) {
      const TriangleMesh gt = read_ply(gt_points);
      if (!mesh.vertices.empty()) {
        PointCloud aligned = mesh.vertices;
        for (auto& p : aligned.points) p = T * p;
        evaluation["semantic"] = to_json(evaluate_semantic(gt.vertices, aligned));
      }
      std::vector<EvalObject> map_objects;
      for (const auto& inst : objects.instances()) {
        EvalObject o{inst.id, inst.class_id(), inst.points};
        for (auto& p : o.points) p = T * p;
        map_objects.push_back(std::move(o));
      }
      evaluation["objects"] = to_json(evaluate_objects(gt_objects_from_points(gt.vertices), map_objects));
    }
  }

  // --- report -------------------------------------------------------------------------
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  nlohmann::json report;
  report["dataset"] = options.dataset.string();
  report["summary"] = {
      {"frames", frames_done.load()},
      {"frames_skipped", skipped_frames.load()},
      {"keyframes", tracker ? tracker_stats.keyframes : keyframes.load()},
      {"segmented_frames", segmented_frames.load()},
      {"segmentations_dropped", dropped_segmentations.load()},
      {"object_frames", objects_processed.load()},
      {"object_accumulations_skipped", skipped_accumulations.load()},
      {"objects", objects.instances().size()},
      {"poses", options.poses},
      {"segmenter", segmenter ? segmenter->name() : std::string("none")},
      {"loop_edges", tracker_stats.loop_edges},
      {"map_refreshed_with_optimised_poses", map_refreshed},
      {"max_pose_correction_m", max_pose_correction},
      {"refresh_archive_mb", (label_archive.bytes() + repair_archive.bytes()) / (1024.0 * 1024.0)},
      {"mesh_vertices", mesh.vertices.size()},
      {"mesh_triangles", mesh.triangles.size()},
      // online: the stages streaming the frames; end to end: also the final pose-graph pass,
      // map refresh, meshing, evaluation and outputs.
      {"fps_online", frames_done.load() / std::max(online_s, 1e-9)},
      {"fps_end_to_end", frames_done.load() / std::max(wall_s, 1e-9)},
      {"wall_s", wall_s},
      {"peak_rss_mb", peak_rss_bytes() / (1024.0 * 1024.0)},
      {"threads", threads},
  };
  report["objects_per_class"] = objects_per_class(objects);
  report["evaluation"] = evaluation;
  report["timings"] = timings_json(timings);
  if (tracker) {
    report["tracking"] = {{"keyframes", tracker_stats.keyframes}, {"lost_frames", tracker_stats.lost_frames},
                          {"relocalisations", tracker_stats.relocalisations}, {"loop_edges", tracker_stats.loop_edges},
                          {"optimisations", tracker_stats.optimisations}};
  }

  const cv::Mat topdown = render_topdown(mesh, trajectory, report_objects(objects_json));
  write_atomic_with(options.out_dir / "topdown.png", [&](const std::filesystem::path& tmp) {
    if (!cv::imwrite(tmp.string() + ".png", topdown)) throw Error(options.out_dir / "topdown.png", "cannot write");
    std::filesystem::rename(tmp.string() + ".png", tmp);
  });
  write_file_atomic(options.out_dir / "report.json", report.dump(2) + "\n");
  write_report_html(options.out_dir, report);
  if (options.show_progress) progress.finish(progress_extra());
  return report;
}

}  // namespace semap
