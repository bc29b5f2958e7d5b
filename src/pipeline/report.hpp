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
cv::Mat render_topdown(const TriangleMesh& mesh, const Trajectory& trajectory,
                       const std::vector<ReportObject>& objects, int max_side_px = 900);

/// Per-stage timing table as JSON {stage: {count, mean_ms, median_ms, p95_ms}}.
nlohmann::json timings_json(const std::map<std::string, TimingSummary>& timings);

/// Writes report.html beside report.json (reads its figures from `report`), referencing
/// topdown.png in the same folder. Atomic.
void write_report_html(const std::filesystem::path& out_dir, const nlohmann::json& report);

/// A plain-text summary table of the report for the terminal.
std::string summary_table(const nlohmann::json& report);

}  // namespace semap
