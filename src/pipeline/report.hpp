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

/// One object as report.html shows it: a card with a thumbnail (PNG bytes).
struct ObjectCard {
  uint32_t id = 0;
  std::string class_name;
  double confidence = 0.0;                         ///< 0..1, mean detector score
  Eigen::Vector3d size_m = Eigen::Vector3d::Zero();  ///< oriented box extent, metres
  std::string thumbnail_png;
};

/// Cards of the final objects, sorted by class then confidence; thumbnails drawn from each
/// object's coloured voxels seen level (`up_W`) from the side of the camera path.
std::vector<ObjectCard> object_cards(const std::vector<ObjectSummary>& objects, const Eigen::Vector3d& up_W,
                                     const Trajectory& trajectory, int thumbnail_px = 120);

/// Writes report.html into `out_dir` (atomic): a summary in sentences, inline SVG plots and
/// figures with names, units and explanations, read from `report` (the report.json document);
/// topdown.png and the object thumbnails are embedded (data: URIs), so the page stands alone.
void write_report_html(const std::filesystem::path& out_dir, const nlohmann::json& report,
                       const std::string& topdown_png, const std::vector<ObjectCard>& cards);

/// Per-frame columns for report.json "frames": timestamp_s, status, ransac_inliers,
/// tracking_ms, add_frame_ms (one entry per add_frame call, in order), and ate_m (the frame's
/// trajectory error, null where its pose did not associate) when `ate` is given.
nlohmann::json frames_json(const std::vector<FrameResult>& frames, const std::optional<AteResult>& ate);

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
