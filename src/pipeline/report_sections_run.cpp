// report.html sections on how the run went (issue 43): summary sentences, per-frame time and
// tracking, per-frame time of every stage, trajectory error, time per stage.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "pipeline/report_sections.hpp"
#include "pipeline/report_svg.hpp"

namespace semap::report {
namespace {

Reference frame_budget() {
  const double budget_ms = 1000.0 / kTargetFps;
  return {budget_ms, "budget at " + fixed(kTargetFps, 0) + " fps: " + fixed(budget_ms, 1) + " ms"};
}

/// "1 frame lost", "3 frames lost": the count at `path` (0 when absent) with its noun.
std::string counted(const nlohmann::json& r, const std::string& path, const std::string& one, const std::string& many) {
  const double n = number_at(r, path).value_or(0);
  return fixed(n, 0) + " " + (n == 1 ? one : many);
}

std::string tracking_sentence(const nlohmann::json& r) {
  if (!r.contains("tracking")) {
    const std::string poses = r.value("summary", nlohmann::json::object()).value("poses", std::string("given"));
    return "Poses were given (" + html_escape(poses == "given" ? "by the caller" : poses) + "), not tracked. ";
  }
  return counted(r, "tracking/lost_frames", "frame lost", "frames lost") + ", " +
         counted(r, "tracking/relocalisations", "relocalisation", "relocalisations") + ", " +
         counted(r, "tracking/loop_edges", "loop closure", "loop closures") + ". ";
}

/// A --resume run (report.json "resumed", issue 19): whether it continued the saved map.
std::string resumed_sentence(const nlohmann::json& r) {
  if (!r.contains("resumed")) return "";
  const nlohmann::json& resumed = r["resumed"];
  if (resumed.contains("merged") && resumed["merged"] == false)
    return "No frame relocalised into the saved map given with --resume: this recording was mapped on its own. ";
  return "Continued a saved map of " + counted(r, "resumed/saved_keyframes", "keyframe", "keyframes") + " (" +
         counted(r, "resumed/held_frames", "frame", "frames") + " held until the first relocalisation). ";
}

}  // namespace

std::string summary_sentences(const nlohmann::json& r) {
  std::ostringstream h;
  h << "<p class=\"summary\">Mapped " << fixed(number_at(r, "summary/frames").value_or(0), 0) << " frames";
  if (const auto wall = number_at(r, "summary/wall_s"))
    h << " in " << fixed(*wall, 1) << " s (" << value_or(r, "summary/fps_end_to_end", 1, 1, "fps", "?")
      << " end to end, " << value_or(r, "summary/fps_online", 1, 1, "fps", "?") << " while streaming)";
  h << ". " << tracking_sentence(r) << resumed_sentence(r);
  h << fixed(number_at(r, "summary/objects").value_or(0), 0) << " objects";
  if (const auto share = number_at(r, "consistency/labelled_area_share"))
    h << ", " << fixed(*share * 100, 0) << " % of the surface labelled";
  h << ". ";
  if (const auto ate = number_at(r, "evaluation/ate/rmse_m"))
    h << "Trajectory error against ground truth (ATE RMSE): " << fixed(*ate * 100, 1) << " cm.";
  else
    h << "No ground-truth trajectory: the trajectory error (ATE) was not computed.";
  h << "</p>\n";
  return h.str();
}

std::vector<double> frame_column(const nlohmann::json& r, const char* key, double missing) {
  std::vector<double> out;
  if (!r.contains("frames") || !r["frames"].contains(key)) return out;
  for (const auto& v : r["frames"][key]) out.push_back(v.is_number() ? v.get<double>() : missing);
  return out;
}

std::string per_frame_section(const nlohmann::json& r) {
  std::ostringstream h;
  h << "<h2>Time per frame</h2>\n";
  const std::vector<double> total = frame_column(r, "add_frame_ms"), tracking = frame_column(r, "tracking_ms");
  if (total.empty())
    return h.str() + "<p class=\"missing\">This report has no per-frame record, so there is no time or tracking "
                     "plot per frame.</p>\n";
  h << "<p class=\"explain\">Milliseconds the mapper took to accept each frame (tracking plus handing the "
       "frame to fusion and segmentation; waiting on a full queue included) and the tracking part of it. "
       "Above the dashed line (the budget at "
    << fixed(kTargetFps, 0) << " fps) the mapper falls behind a live camera.</p>\n"
    << svg_series_chart({{"accepting the frame", "#4a7ab5", total}, {"tracking", "#e08a1e", tracking}}, "ms",
                        frame_budget());
  h << "<h2>Tracking over time</h2>\n";
  if (!r.contains("tracking"))
    return h.str() + "<p class=\"missing\">Poses were given, not tracked: no tracking status or inlier count.</p>\n";
  std::vector<std::string> status;
  if (r["frames"].contains("status"))
    for (const auto& v : r["frames"]["status"]) status.push_back(v.is_string() ? v.get<std::string>() : "?");
  h << "<p class=\"explain\">Status of each frame: tracked, made a new keyframe, lost (not fused into the map) "
       "or relocalised after a loss. Below: RANSAC inliers, the feature matches that agree with the estimated "
       "motion; few inliers is where tracking struggled.</p>\n"
    << svg_status_strip(status) << svg_series_chart({{"RANSAC inliers", "#2ca02c", frame_column(r, "ransac_inliers")}}, "inliers");
  return h.str();
}

namespace {

/// The stages timed per frame, in pipeline order (others after, by name).
std::vector<std::string> stages_in_pipeline_order(const nlohmann::json& stage_ms) {
  static const std::vector<std::string> kOrder = {"read", "depth_repair", "tracking", "segmentation",
                                                  "semantic_segmentation", "tsdf_integration", "refresh_archive",
                                                  "object_accumulate", "object_map"};
  std::vector<std::string> out;
  for (const std::string& s : kOrder)
    if (stage_ms.contains(s)) out.push_back(s);
  for (auto it = stage_ms.begin(); it != stage_ms.end(); ++it)
    if (std::find(kOrder.begin(), kOrder.end(), it.key()) == kOrder.end()) out.push_back(it.key());
  return out;
}

/// The top of a stage's strip: the 99th percentile of its times, so one stall does not flatten
/// the strip, and at least 1.2 budgets, so stages within the budget share one scale and show
/// the budget line.
double strip_top_ms(const Series& series, double budget_ms) {
  std::vector<double> finite;
  for (double v : series.values)
    if (std::isfinite(v)) finite.push_back(v);
  if (finite.empty()) return 1.2 * budget_ms;
  const size_t k = std::min(finite.size() - 1, static_cast<size_t>(0.99 * static_cast<double>(finite.size() - 1) + 0.5));
  std::nth_element(finite.begin(), finite.begin() + static_cast<std::ptrdiff_t>(k), finite.end());
  return std::max(1.2 * budget_ms, finite[k]);
}

}  // namespace

std::string stage_frames_section(const nlohmann::json& r) {
  std::ostringstream h;
  h << "<h2>Time of each stage per frame</h2>\n";
  const nlohmann::json stage_ms =
      r.contains("frames") ? r["frames"].value("stage_ms", nlohmann::json::object()) : nlohmann::json::object();
  static const std::vector<std::string> kColours = {"#4a7ab5", "#e08a1e", "#2ca02c", "#d62728", "#9467bd",
                                                    "#8c564b", "#e377c2", "#17becf", "#7f7f7f"};
  std::vector<Series> series;
  for (const std::string& stage : stages_in_pipeline_order(stage_ms)) {
    Series s{stage_label(stage), kColours[series.size() % kColours.size()], {}};
    for (const auto& v : stage_ms[stage]) s.values.push_back(v.is_number() ? v.get<double>() : std::nan(""));
    series.push_back(std::move(s));
  }
  if (series.empty())
    return h.str() + "<p class=\"missing\">No stage was timed per frame in this run.</p>\n";
  const Reference budget = frame_budget();
  std::vector<double> tops;
  for (const Series& s : series) tops.push_back(strip_top_ms(s, budget.value));
  h << "<p class=\"explain\">Milliseconds each stage spent on each frame, one strip per stage (its scale on the "
       "right: the same for the stages within the budget, its own for a slower one, whose rare stalls above it are "
       "clipped), the dashed line the frame budget at "
    << fixed(kTargetFps, 0)
    << " fps. A gap is a frame the stage did not run on (segmentation every few frames, the object map on its "
       "keyframes). Stages on their own threads (segmentation, fusion, objects) overlap tracking, so a frame's "
       "times do not add up to its delay; a stage above the line on most frames falls behind a live camera.</p>\n"
    << svg_series_strips(series, "ms", tops, budget);
  return h.str();
}

std::string ate_section(const nlohmann::json& r) {
  std::ostringstream h;
  h << "<h2>Trajectory error over time</h2>\n";
  std::vector<double> ate_cm = frame_column(r, "ate_m", std::numeric_limits<double>::quiet_NaN());
  if (std::none_of(ate_cm.begin(), ate_cm.end(), [](double v) { return std::isfinite(v); }))
    return h.str() + "<p class=\"missing\">" +
           (r.contains("tracking") ? "No ground-truth trajectory was compared: no trajectory error per frame."
                                   : "Poses were given, not estimated: there is no trajectory error to plot.") +
           "</p>\n";
  for (double& v : ate_cm) v *= 100.0;
  h << "<p class=\"explain\">Distance in centimetres between each estimated camera position and the "
       "ground truth, after the one rigid alignment of the whole trajectory (ATE). A rise is where the "
       "estimate drifted; a drop after a loop closure is the correction.</p>\n"
    << svg_series_chart({{"trajectory error (ATE)", "#9467bd", ate_cm}}, "cm");
  return h.str();
}

std::string stage_label(const std::string& key) {
  static const std::map<std::string, std::string> kLabels = {
      {"read", "reading the frame"},          {"depth_repair", "depth repair"},
      {"tracking", "tracking"},               {"segmentation", "segmentation"},
      {"semantic_segmentation", "semantic segmentation"}, {"tsdf_integration", "fusion into the TSDF"},
      {"object_accumulate", "object evidence"}, {"object_map", "object map update"},
      {"refresh_archive", "keeping frames for refresh"}, {"map_refresh", "map rebuilt with loop-closed poses"},
      {"pose_graph_final", "final pose graph"}, {"object_map_final", "final object map"}};
  const auto it = kLabels.find(key);
  return it == kLabels.end() ? key : it->second;
}

namespace {

std::string duration_text(double ms) { return ms >= 1000.0 ? fixed(ms / 1000.0, 1) + " s" : fixed(ms, 1) + " ms"; }

}  // namespace

std::string timing_section(const nlohmann::json& r) {
  std::ostringstream h;
  h << "<h2>Time per stage</h2>\n";
  const nlohmann::json t = r.value("timings", nlohmann::json::object());
  std::vector<Bar> bars;
  std::vector<std::string> once;  // stages run once at the end: a sentence, not a bar that dwarfs the rest
  for (auto it = t.begin(); it != t.end(); ++it) {
    const auto mean = number_at(*it, "mean_ms");
    if (!mean) continue;
    const double count = number_at(*it, "count").value_or(0);
    if (count <= 1) {
      once.push_back(stage_label(it.key()) + " " + duration_text(*mean));
      continue;
    }
    const auto p95 = number_at(*it, "p95_ms");
    bars.push_back({stage_label(it.key()), *mean, p95, "#4a7ab5",
                    fixed(*mean, 1) + " ms" + (p95 ? " (p95 " + fixed(*p95, 1) + ")" : "") + ", " + fixed(count, 0) +
                        " calls"});
  }
  if (bars.empty() && once.empty()) return h.str() + "<p class=\"missing\">No stage was timed in this run.</p>\n";
  h << "<p class=\"explain\">Bar: mean wall time of one call of each stage, in milliseconds; black tick: 95th "
       "percentile (the slow calls); dashed red line: the frame budget at "
    << fixed(kTargetFps, 0)
    << " fps. Stages on their own thread (segmentation, fusion, objects) overlap tracking; a stage slower than the "
       "budget falls behind a live camera or skips frames.</p>\n";
  if (!bars.empty()) h << svg_bar_chart(bars, "ms", frame_budget());
  if (!once.empty()) {
    h << "<p>Once, after the last frame: ";
    for (size_t i = 0; i < once.size(); ++i) h << (i ? ", " : "") << html_escape(once[i]);
    h << ".</p>\n";
  }
  return h.str();
}

}  // namespace semap::report
