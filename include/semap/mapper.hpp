#pragma once
// semap::Mapper: the per-frame library API. Frames in, a trajectory, a labelled mesh and an
// object map out. The dataset loop lives outside (run_pipeline, the Python module, a robot's
// driver): the Mapper never opens a file.
//
//   semap::Mapper mapper(config, camera);        // + optionally a segmenter
//   for (const semap::Frame& frame : frames) {
//     const semap::FrameResult r = mapper.add_frame(frame);
//     // r.T_world_camera, r.status
//   }
//   mapper.finish();                             // final pose graph, map refresh, object pass
//   semap::write_map_outputs(mapper, "out");     // trajectory, mesh, objects, map.semap
//
// Conventions: poses are T_world_camera (camera-to-world, metres). The world frame is the
// first frame's camera when semap tracks, or the caller's frame when the caller gives poses.
// Depth is CV_32FC1 metres (0 = invalid) at the camera's depth resolution; colour is CV_8UC3
// BGR (OpenCV order) at the colour resolution (METHODS.md B2 registers it to depth). Frames
// are given as the camera took them: with CameraModel::distortion set, add_frame undistorts
// them once and every stage and output works in the pinhole image of the same intrinsics.
//
// Inside, tracking (METHODS A1-A4) runs on the caller's thread; segmentation (C1, B1), TSDF
// fusion (B3-B7, A6) and the object map (C2-C5) run on their own threads behind bounded
// queues when pipeline.threads > 1. With pipeline.threads = 1 every stage runs inline in
// add_frame() in one fixed order, and outputs are byte-identical from run to run.
//
// Thread safety: add_frame(), finish() and save() must be called from one thread at a time
// (the driver). Every const accessor (trajectory, mesh, objects, read_tsdf, stats) may be
// called from any thread at any time, also while add_frame() runs on another.
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"
#include "semap/core/point_cloud.hpp"
#include "semap/core/pose.hpp"
#include "semap/objects/object_summary.hpp"
#include "semap/pipeline/semap_config.hpp"
#include "semap/pipeline/stage_timer.hpp"
#include "semap/segmentation/segmenter.hpp"
#include "semap/tsdf/tsdf_map.hpp"

namespace semap {

/// What happened to a frame's pose.
enum class FrameStatus {
  tracking,     ///< tracked against the current keyframe
  keyframe,     ///< tracked and became a new keyframe
  lost,         ///< registration failed its checks: the frame is not fused into the map
  relocalised,  ///< tracking was lost and this frame recovered it through the keyframe database
};
const char* to_string(FrameStatus status);

/// Optional inputs a caller may give with a frame instead of letting the Mapper compute them.
struct FrameHints {
  /// External pose (ground truth, wheel/VIO odometry): the Mapper does not track this frame.
  /// Either every frame of a Mapper has one or none has (the first frame decides).
  std::optional<Pose> T_world_camera;
  /// The caller's own segmentation of this frame (project class ids, masks at depth
  /// resolution): the Mapper's segmenter is not run on it. See segmentation_from_label_images().
  std::optional<SegmentationResult> segmentation;
};

struct FrameResult {
  size_t frame_index = 0;  ///< Frame::index as given
  double timestamp = 0.0;  ///< seconds
  Pose T_world_camera = Pose::Identity();  ///< online estimate (finish() refines it)
  FrameStatus status = FrameStatus::tracking;
  bool fused = false;      ///< handed to TSDF fusion (false for lost frames)
  bool segmented = false;  ///< sent to segmentation (or came with its own)
  double tracking_ms = 0.0;  ///< time add_frame spent tracking
  double total_ms = 0.0;     ///< time add_frame took (waiting on a full queue included)
  int ransac_inliers = 0;    ///< voting-RANSAC inliers of the tracking estimate (0: pose given, or RANSAC failed)
};

/// Counters of the run so far. A snapshot; cheap.
struct MapperStats {
  size_t frames = 0;            ///< add_frame() calls
  size_t frames_fused = 0;      ///< frames integrated into the TSDF
  size_t keyframes = 0, lost_frames = 0, relocalisations = 0, loop_edges = 0, optimisations = 0;
  size_t local_edges = 0;  ///< keyframe-to-nearby-keyframe pose-graph edges (tracking.local_edge_keyframes)
  size_t segmented_frames = 0;       ///< frames the segmenter ran on (or that came with labels); panoptic: its instance network
  size_t semantic_segmented_frames = 0;  ///< panoptic: frames its semantic network ran on (its own schedule)
  size_t segmentations_dropped = 0;  ///< requests dropped because the network was busy
  size_t segmentations_failed = 0;   ///< the segmenter threw on the frame (warned)
  std::string segmentation_error;    ///< the first such error
  size_t object_frames = 0;          ///< object-map keyframes processed (C2-C4)
  size_t object_accumulations_skipped = 0;
  size_t objects = 0;                ///< instances in the object map
  size_t objects_created = 0;        ///< after finish(): instances created by association (C4) ...
  size_t objects_deleted = 0;        ///< ... removed by the C5 deletion (too few associations) ...
  size_t objects_merged = 0;         ///< ... and by the C5 merge (the rest folded at association)
  bool finished = false;
  bool map_refreshed = false;         ///< finish() rebuilt the TSDF with the optimised poses
  std::string map_refresh_note;       ///< why it did not, when it did not
  double max_pose_correction_m = 0.0; ///< largest surface displacement of the final pass
  size_t refresh_archive_bytes = 0;   ///< memory kept for the refresh
  bool external_poses = false;        ///< the caller gave the poses
  size_t resumed_keyframes = 0;       ///< keyframes of the saved map this Mapper continues (load())
  size_t held_frames = 0;             ///< frames held (not fused, no pose) before relocalising into it
  /// Issue 42: registrations verified, and how often each check failed (TrackerStats).
  size_t verified_registrations = 0, dense_residual_failed = 0, spread_failed = 0, ambiguous_matches = 0,
         under_constrained = 0;
  std::string segmenter = "none";
};

/// Gives finish() a frame again when loop closure moved the frames and the map is rebuilt
/// with the optimised poses. Must return the frame as it was passed to add_frame (same images;
/// colour may be skipped when `need_colour` is false). Called concurrently from worker threads.
/// Throws semap::Error when it cannot (the frame is then left out of the rebuilt map).
using FrameReloader = std::function<Frame(size_t frame_index, bool need_colour)>;

class Mapper {
 public:
  /// Validates `config` and the camera (throws semap::Error). Without a segmenter the one named
  /// by config.segmentation.segmenter is built ("none": geometry and colour only).
  Mapper(const SemapConfig& config, const CameraModel& camera, std::unique_ptr<Segmenter> segmenter = nullptr);
  ~Mapper();
  Mapper(const Mapper&) = delete;
  Mapper& operator=(const Mapper&) = delete;

  /// Tracks the frame (or takes hints.T_world_camera), schedules its segmentation and fuses it.
  /// Frames come in sequence order. Throws semap::Error naming the frame for images of the wrong
  /// type or size, a missing pose when poses are external, or a call after finish().
  FrameResult add_frame(const Frame& frame, FrameHints hints = {});
  /// Waits for the stages, runs the final pose-graph optimisation, rebuilds the TSDF with the
  /// optimised poses when loop closure moved them (needs the frames again: set_frame_reloader,
  /// else the Mapper's own bounded copy of them), and the final object-map pass (C5). Idempotent.
  void finish();
  /// How finish() gets frames again; without one the Mapper keeps compressed copies of the
  /// frames in memory up to pipeline.refresh_cache_mb. Call before the first add_frame().
  void set_frame_reloader(FrameReloader reloader);

  /// Every frame so far with its current pose estimate (the optimised ones after finish()).
  Trajectory trajectory() const;
  /// The labelled mesh extracted now (METHODS B7): vertices with RGB colour, class id and the
  /// id of the object they belong to (0 = none); only changed blocks are re-meshed.
  TriangleMesh mesh() const;
  /// The object map now (C2-C5).
  std::vector<ObjectSummary> objects() const;
  /// Calls `reader` with the TSDF, locked against fusion for the duration of the call (ray
  /// casting, queries). Do not keep references past the call.
  void read_tsdf(const std::function<void(const TsdfMap&)>& reader) const;
  MapperStats stats() const;
  /// Every add_frame() result so far, in call order: the per-frame plots of report.html
  /// (issue 43). A copy; thread-safe.
  std::vector<FrameResult> frame_results() const;
  /// Per-stage timings (read, tracking, segmentation, tsdf_integration, object_map, ...).
  std::map<std::string, TimingSummary> timings() const;
  /// Adds a caller-side stage timing (e.g. "read") to timings().
  void add_timing(const std::string& stage, double ms);
  /// The same, wall and CPU time since `start` (taken on the calling thread), of the work on
  /// the frame `frame_index` (Frame::index) when it was one frame's.
  void add_timing(const std::string& stage, const StageStart& start, std::optional<size_t> frame_index = std::nullopt);
  /// Every timed call of every stage so far, with the frame it worked on: the per-frame stage
  /// times of report.html (issue 43). A copy; thread-safe.
  std::map<std::string, std::vector<StageSample>> stage_samples() const;

  const SemapConfig& config() const;
  const CameraModel& camera() const;
  /// Writes the whole map (map.semap, versioned, checksummed) atomically: the TSDF with its
  /// label layers, the object map with each object's best view, the keyframe database and pose
  /// graph (tracked runs), the camera and the configuration. load() continues it.
  void save(const std::filesystem::path& path) const;
  /// The same with sections of other stages added (issue 39: "gravity"); a name the Mapper
  /// writes itself is not replaced.
  void save(const std::filesystem::path& path, const std::map<std::string, std::string>& extra_sections) const;

  /// Continues the map saved in `path` by save() (issue 19): TSDF, objects and keyframes come
  /// from the file, in its world frame. The first frames are relocalised against the saved
  /// keyframes (METHODS A3) and held (status lost: no pose, not fused) until one verifies; then
  /// tracking, fusion and the object map extend the saved map, the saved keyframes fixed in
  /// the pose graph. The configuration is the file's unless `config` is given (its tsdf and
  /// objects sections are then still the file's: the saved voxels and object points were made
  /// with them; its fern parameters must match the file's); the camera is the file's. A map made with external poses has no keyframes: it continues only
  /// with poses given by the caller. Saving right after loading writes the same bytes. Throws
  /// semap::Error naming the file for an unreadable, corrupt, old or foreign file.
  static std::unique_ptr<Mapper> load(const std::filesystem::path& path, std::optional<SemapConfig> config = std::nullopt,
                                      std::unique_ptr<Segmenter> segmenter = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The segmentation a caller computed itself, from a label image (CV_8UC1 project class ids)
/// and an optional instance image (CV_16UC1 ids, 0 = none): one instance per instance id, its
/// class the majority label under its mask (see GroundTruthSegmenter).
SegmentationResult segmentation_from_label_images(const cv::Mat& labels, const cv::Mat& instances = {});

}  // namespace semap
