#pragma once
// report.json / report.html / topdown.png: what a person reads after a run (issue 7).
#include <Eigen/Core>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "semap/core/point_cloud.hpp"
#include "semap/core/pose.hpp"
#include "semap/navigation/occupancy_grid.hpp"
#include "semap/pipeline/outputs.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "semap/pipeline/stage_timer.hpp"

namespace semap {

/// An object box to draw: 8 world-frame corners of its oriented box.
struct ReportObject {
  uint32_t id = 0;
  ClassId class_id = 0;
  std::array<Eigen::Vector3d, 8> corners;
};

/// Top-down orthographic picture of the labelled mesh (ceiling cut away), object boxes with
/// class names and the camera trajectory. "Up" is estimate_gravity's (core/gravity.hpp).
/// trajectory_error_m: (pose timestamp s, ATE m) pairs (AteResult::per_pose_error_m) that colour
/// the trajectory green to red; empty: drawn dark grey.
cv::Mat render_topdown(const TriangleMesh& mesh, const Trajectory& trajectory,
                       const std::vector<ReportObject>& objects, int max_side_px = 900,
                       const std::vector<std::pair<double, double>>& trajectory_error_m = {});

/// Per-stage timing table as JSON {stage: {count, mean_ms, median_ms, p95_ms}}.
nlohmann::json timings_json(const std::map<std::string, TimingSummary>& timings);

/// Where an object card's thumbnail comes from.
enum class ThumbnailSource {
  camera_crop,  ///< the colour image of the keyframe that saw the object best (ObjectSummary::best_view_jpeg)
  voxels,       ///< no such view (e.g. a map saved by an older semap): its coloured voxels drawn
};

/// One object as report.html shows it: a card with a thumbnail.
struct ObjectCard {
  uint32_t id = 0;
  std::string class_name;
  double confidence = 0.0;                         ///< 0..1, mean detector score
  Eigen::Vector3d size_m = Eigen::Vector3d::Zero();  ///< oriented box extent, metres
  std::string thumbnail;                           ///< encoded image bytes
  std::string thumbnail_mime = "image/png";
  ThumbnailSource thumbnail_source = ThumbnailSource::voxels;
};

/// Cards of the final objects, sorted by class then confidence. Thumbnail: the object's best
/// camera view when it has one, else drawn from its coloured voxels seen level (`up_W`) from
/// the side of the camera path.
std::vector<ObjectCard> object_cards(const std::vector<ObjectSummary>& objects, const Eigen::Vector3d& up_W,
                                     const Trajectory& trajectory, int thumbnail_px = 96);

/// The occupancy grid as report.html shows it (issue 39): free white, unknown grey, occupied
/// in the class colour of its top surface (black: unlabelled), the camera path over it.
struct GridPicture {
  std::string png;                 ///< empty: the run made no grid (nothing mapped in the band)
  std::vector<ClassId> classes;    ///< classes of the occupied cells, most cells first (legend)
  double resolution_m = 0.0;
  int width_cells = 0, height_cells = 0;
  size_t free_cells = 0, occupied_cells = 0, unknown_cells = 0;
};
/// Draws `grid` in map.pgm's orientation (first row: the highest y of the gravity frame),
/// square cells of a whole number of pixels (1 to 12), its longer side up to `max_side_px`, with
/// the camera path `trajectory` (world frame) over it.
GridPicture render_grid_picture(const OccupancyGrid& grid, const Trajectory& trajectory, int max_side_px = 640);

/// What report.html embeds besides report.json (data: URIs, so the page stands alone).
struct ReportPictures {
  std::string topdown_png;
  GridPicture grid;
  std::vector<ObjectCard> cards;
};

/// Writes report.html into `out_dir` (atomic): a summary in sentences, inline SVG plots and
/// figures with names, units and explanations, read from `report` (the report.json document),
/// and the pictures.
void write_report_html(const std::filesystem::path& out_dir, const nlohmann::json& report,
                       const ReportPictures& pictures);

/// Per-frame columns for report.json "frames": timestamp_s, status, ransac_inliers,
/// tracking_ms, add_frame_ms (one entry per add_frame call, in order); stage_ms: per stage
/// timed per frame, its milliseconds on each frame (summed when it ran twice, null when it did
/// not run on the frame); and ate_m (the frame's trajectory error, null where its pose did not
/// associate) when `ate` is given.
nlohmann::json frames_json(const std::vector<FrameResult>& frames,
                           const std::map<std::string, std::vector<StageSample>>& stage_samples,
                           const std::optional<AteResult>& ate);

/// Number of objects per class name (report.json "objects_per_class").
std::map<std::string, int> objects_per_class(const std::vector<ObjectSummary>& objects);

/// Object boxes as the top-down picture draws them.
std::vector<ReportObject> report_objects(const std::vector<ObjectSummary>& objects);

/// Writes topdown.png, report.json and report.html into `dir` (each atomic): the run's figures
/// plus the map's consistency, gravity and navigation figures. Used by `semap run` and by
/// write_map_outputs(mapper, dir), so the CLI, Python and C++ give the same files (issue 43).
void write_run_report(const std::filesystem::path& dir, const RunResult& result, const MapOutputs& outputs);

/// The RunResult a Mapper driven by a library caller can give: its stats, timings, mesh and
/// objects; the wall/fps/CPU figures only a driver measures stay unmeasured (driver_measured).
RunResult library_run_result(const Mapper& mapper, const MapOutputs& outputs);

/// A plain-text summary table of the report for the terminal.
std::string summary_table(const nlohmann::json& report);

}  // namespace semap
