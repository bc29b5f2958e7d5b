// report.html (issue 43): a page a person reads after a run. A summary in sentences, plots
// drawn as inline SVG by semap (no script, no network, no CDN) and every figure with a readable
// name, a unit and a one-line explanation. Raw keys stay in report.json for scripts.
#include <algorithm>
#include <array>
#include <functional>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "core/paths.hpp"
#include "pipeline/report.hpp"
#include "semap/core/labels.hpp"

namespace semap {
namespace {

/// The frame budget drawn on the stage-time plot: the 30 Hz of the RGB-D sensors semap reads
/// (TUM, 7-Scenes, Replica renders). A display reference, not a tuning parameter.
constexpr double kReportTargetFps = 30.0;

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

/// A finite number at `path` ("a/b/c") in `j`, or nullopt (missing, null, NaN, not a number).
std::optional<double> number_at(const nlohmann::json& j, const std::string& path) {
  const nlohmann::json* node = &j;
  std::stringstream parts(path);
  for (std::string key; std::getline(parts, key, '/');) {
    if (!node->is_object() || !node->contains(key)) return std::nullopt;
    node = &(*node)[key];
  }
  if (!node->is_number()) return std::nullopt;
  const double v = node->get<double>();
  return std::isfinite(v) ? std::optional<double>(v) : std::nullopt;
}

std::string hex_colour(Rgb8 c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c.r, c.g, c.b);
  return buf;
}

/// One bar of a horizontal bar chart; `whisker` (same unit, >= value) draws a tick, e.g. p95.
struct Bar {
  std::string label;
  double value = 0;
  std::optional<double> whisker;
  std::string colour = "#4a7ab5";
  std::string value_text;
};

/// Horizontal bar chart as inline SVG: one row per bar, label left, value right of the bar, so
/// labels never overlap. `reference` draws a dashed vertical line (e.g. the frame budget).
std::string svg_bar_chart(const std::vector<Bar>& bars, const std::string& unit,
                          std::optional<std::pair<double, std::string>> reference = std::nullopt) {
  const int row_px = 22, label_px = 230, plot_px = 480, value_px = 250, top_px = 24;
  double max_v = reference ? reference->first : 0.0;
  for (const Bar& b : bars) max_v = std::max({max_v, b.value, b.whisker.value_or(0.0)});
  if (max_v <= 0) max_v = 1;
  const auto x_of = [&](double v) { return label_px + plot_px * std::clamp(v / max_v, 0.0, 1.0); };
  const int height = top_px + row_px * static_cast<int>(bars.size()) + 8;
  std::ostringstream s;
  s << "<svg class=\"plot\" width=\"" << label_px + plot_px + value_px
    << "\" height=\"" << height << "\" font-size=\"12\" font-family=\"sans-serif\">\n";
  s << "<text x=\"" << label_px << "\" y=\"14\" fill=\"#555\">0</text><text x=\"" << label_px + plot_px
    << "\" y=\"14\" text-anchor=\"end\" fill=\"#555\">" << html_escape(fixed(max_v, max_v < 10 ? 1 : 0) + " " + unit)
    << "</text>\n";
  for (size_t i = 0; i < bars.size(); ++i) {
    const Bar& b = bars[i];
    const int y = top_px + row_px * static_cast<int>(i);
    s << "<text x=\"" << label_px - 6 << "\" y=\"" << y + 14 << "\" text-anchor=\"end\">" << html_escape(b.label)
      << "</text>";
    s << "<rect class=\"datum\" x=\"" << label_px << "\" y=\"" << y + 3 << "\" width=\""
      << fixed(std::max(1.0, x_of(b.value) - label_px), 1) << "\" height=\"" << row_px - 6 << "\" fill=\"" << b.colour
      << "\"><title>" << html_escape(b.label + ": " + b.value_text) << "</title></rect>";
    if (b.whisker)
      s << "<line x1=\"" << fixed(x_of(*b.whisker), 1) << "\" x2=\"" << fixed(x_of(*b.whisker), 1) << "\" y1=\"" << y + 2
        << "\" y2=\"" << y + row_px - 2 << "\" stroke=\"#222\" stroke-width=\"2\"/>";
    const double text_x = std::max(x_of(b.value), b.whisker ? x_of(*b.whisker) : 0.0) + 6;
    s << "<text x=\"" << fixed(text_x, 1) << "\" y=\"" << y + 14 << "\">" << html_escape(b.value_text) << "</text>\n";
  }
  if (reference) {
    const double x = x_of(reference->first);
    s << "<line x1=\"" << fixed(x, 1) << "\" x2=\"" << fixed(x, 1) << "\" y1=\"18\" y2=\"" << height
      << "\" stroke=\"#c0392b\" stroke-dasharray=\"5,3\"/><text x=\"" << fixed(x - 4, 1)
      << "\" y=\"" << height - 2 << "\" text-anchor=\"end\" fill=\"#c0392b\">" << html_escape(reference->second)
      << "</text>\n";
  }
  s << "</svg>\n";
  return s.str();
}

/// A readable figure: name, value with unit, one-line explanation. Missing values say why.
struct Figure {
  std::string name, value, explanation;
};

std::string figure_table(const std::vector<Figure>& figures) {
  std::ostringstream s;
  s << "<table class=\"figures\"><tr><th>figure</th><th>value</th><th>what it means</th></tr>\n";
  for (const Figure& f : figures)
    s << "<tr><td>" << html_escape(f.name) << "</td><td class=\"num\">" << html_escape(f.value) << "</td><td>"
      << html_escape(f.explanation) << "</td></tr>\n";
  s << "</table>\n";
  return s.str();
}

/// value + unit, or `missing` when the report has no finite number there.
std::string value_or(const nlohmann::json& r, const std::string& path, double scale, int decimals,
                     const std::string& unit, const std::string& missing) {
  const auto v = number_at(r, path);
  return v ? fixed(*v * scale, decimals) + (unit.empty() ? "" : " " + unit) : missing;
}

std::string summary_sentences(const nlohmann::json& r) {
  const nlohmann::json s = r.value("summary", nlohmann::json::object());
  std::ostringstream h;
  const double frames = number_at(r, "summary/frames").value_or(0);
  h << "<p class=\"summary\">Mapped " << fixed(frames, 0) << " frames";
  if (const auto wall = number_at(r, "summary/wall_s"))
    h << " in " << fixed(*wall, 1) << " s (" << value_or(r, "summary/fps_end_to_end", 1, 1, "fps", "?")
      << " end to end, " << value_or(r, "summary/fps_online", 1, 1, "fps", "?") << " while streaming)";
  h << ". ";
  if (r.contains("tracking"))
    h << fixed(number_at(r, "tracking/lost_frames").value_or(0), 0) << " frames lost, "
      << fixed(number_at(r, "tracking/relocalisations").value_or(0), 0) << " relocalisations, "
      << fixed(number_at(r, "tracking/loop_edges").value_or(0), 0) << " loop closures. ";
  else
    h << "Poses were given (" << html_escape(s.value("poses", std::string("external"))) << "), not tracked. ";
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

/// RFC 4648 base64, for the data: URIs that embed the images.
std::string base64(const std::string& bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t v = static_cast<uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<uint8_t>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) v |= static_cast<uint8_t>(bytes[i + 2]);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[v & 63] : '=';
  }
  return out;
}

std::string png_img(const std::string& png, const std::string& alt, const std::string& css_class) {
  return "<img class=\"" + css_class + "\" src=\"data:image/png;base64," + base64(png) + "\" alt=\"" + html_escape(alt) +
         "\">";
}

std::string object_cards_section(const std::vector<ObjectCard>& cards) {
  std::ostringstream h;
  h << "<h2>Objects</h2>\n";
  if (cards.empty()) return h.str() + "<p class=\"missing\">No object instance was kept in this run.</p>\n";
  h << "<p class=\"explain\">Each object of the final map: class, detector confidence (mean score of the "
       "detections merged into it, 0-100 %), size of its box in metres (longest side first), and its surface "
       "voxels drawn in their colours, seen level from the camera's side.</p>\n<div class=\"cards\">\n";
  for (const ObjectCard& c : cards) {
    std::array<double, 3> size{c.size_m.x(), c.size_m.y(), c.size_m.z()};
    std::sort(size.begin(), size.end(), std::greater<>());
    h << "<div class=\"card\">" << png_img(c.thumbnail_png, c.class_name + " " + std::to_string(c.id), "thumb")
      << "<div><b>" << html_escape(c.class_name) << "</b> #" << c.id << "</div><div>confidence "
      << fixed(c.confidence * 100, 0) << " %</div><div>" << fixed(size[0], 2) << " x " << fixed(size[1], 2) << " x "
      << fixed(size[2], 2) << " m</div></div>\n";
  }
  h << "</div>\n";
  return h.str();
}

/// One line of a per-frame chart.
struct Series {
  std::string name, colour;
  std::vector<double> values;  ///< one per frame
};

constexpr int kPlotLeftPx = 60, kPlotWidthPx = 800, kPlotHeightPx = 160;

/// Per-frame line chart as inline SVG: x = frame number, y from 0 to the largest value (or the
/// reference line). Long runs are drawn with at most one point per pixel column (its maximum,
/// so spikes stay visible). Legend below the plot, so it covers no data.
std::string svg_series_chart(const std::vector<Series>& series, const std::string& y_unit,
                             std::optional<std::pair<double, std::string>> reference = std::nullopt) {
  size_t n = 0;
  double max_v = reference ? reference->first * 1.2 : 0.0;
  for (const Series& l : series) {
    n = std::max(n, l.values.size());
    for (double v : l.values)
      if (std::isfinite(v)) max_v = std::max(max_v, v);
  }
  if (max_v <= 0) max_v = 1;
  const int top = 10, legend_y = top + kPlotHeightPx + 34;
  const auto y_of = [&](double v) { return top + kPlotHeightPx * (1.0 - std::clamp(v / max_v, 0.0, 1.0)); };
  std::ostringstream s;
  s << "<svg class=\"plot\" width=\"" << kPlotLeftPx + kPlotWidthPx + 20 << "\" height=\"" << legend_y + 10
    << "\" font-size=\"12\" font-family=\"sans-serif\">\n";
  s << "<rect x=\"" << kPlotLeftPx << "\" y=\"" << top << "\" width=\"" << kPlotWidthPx << "\" height=\"" << kPlotHeightPx
    << "\" fill=\"#fafafa\" stroke=\"#bbb\"/>\n";
  for (double f : {0.0, 0.5, 1.0})
    s << "<text x=\"" << kPlotLeftPx - 4 << "\" y=\"" << fixed(y_of(f * max_v) + 4, 1) << "\" text-anchor=\"end\">"
      << fixed(f * max_v, max_v < 10 ? 1 : 0) << "</text>";
  s << "<text x=\"4\" y=\"" << top + kPlotHeightPx / 2 << "\" fill=\"#555\">" << html_escape(y_unit) << "</text>";
  s << "<text x=\"" << kPlotLeftPx << "\" y=\"" << top + kPlotHeightPx + 14 << "\">frame 1</text><text x=\""
    << kPlotLeftPx + kPlotWidthPx << "\" y=\"" << top + kPlotHeightPx + 14 << "\" text-anchor=\"end\">frame " << n
    << "</text>\n";
  const size_t columns = std::min<size_t>(n, kPlotWidthPx);
  int legend_x = kPlotLeftPx;
  for (const Series& l : series) {
    if (l.values.empty()) continue;
    s << "<polyline class=\"datum\" fill=\"none\" stroke=\"" << l.colour << "\" stroke-width=\"1.2\" points=\"";
    for (size_t c = 0; c < columns; ++c) {
      const size_t a = c * l.values.size() / columns, b = std::max(a + 1, (c + 1) * l.values.size() / columns);
      double v = std::numeric_limits<double>::quiet_NaN();  // frames without a value (no ATE): no point
      for (size_t k = a; k < std::min(b, l.values.size()); ++k)
        if (std::isfinite(l.values[k]) && !(v >= l.values[k])) v = l.values[k];
      if (!std::isfinite(v)) continue;
      const double x = kPlotLeftPx + (columns > 1 ? kPlotWidthPx * static_cast<double>(c) / (columns - 1) : 0.0);
      s << fixed(x, 1) << "," << fixed(y_of(v), 1) << " ";
    }
    s << "\"/>\n<rect x=\"" << legend_x << "\" y=\"" << legend_y - 9 << "\" width=\"14\" height=\"4\" fill=\"" << l.colour
      << "\"/><text x=\"" << legend_x + 18 << "\" y=\"" << legend_y << "\">" << html_escape(l.name) << "</text>\n";
    legend_x += 40 + 7 * static_cast<int>(l.name.size());
  }
  if (reference) {
    const double y = y_of(reference->first);
    s << "<line x1=\"" << kPlotLeftPx << "\" x2=\"" << kPlotLeftPx + kPlotWidthPx << "\" y1=\"" << fixed(y, 1) << "\" y2=\""
      << fixed(y, 1) << "\" stroke=\"#c0392b\" stroke-dasharray=\"5,3\"/><text x=\"" << legend_x << "\" y=\"" << legend_y
      << "\" fill=\"#c0392b\">- - " << html_escape(reference->second) << "</text>\n";
  }
  s << "</svg>\n";
  return s.str();
}

std::string status_colour(const std::string& status) {
  if (status == "keyframe") return "#2e6fbd";
  if (status == "lost") return "#d62728";
  if (status == "relocalised") return "#ff9f1a";
  return "#7fbf7f";  // tracking
}

/// Tracking status over time: one coloured band, a run of equal statuses per rectangle, and a
/// legend with the count of each status.
std::string svg_status_strip(const std::vector<std::string>& status) {
  const int top = 4, band_px = 26, legend_y = top + band_px + 18;
  std::ostringstream s;
  s << "<svg class=\"plot\" width=\"" << kPlotLeftPx + kPlotWidthPx + 20 << "\" height=\"" << legend_y + 8
    << "\" font-size=\"12\" font-family=\"sans-serif\">\n";
  const double px_per_frame = static_cast<double>(kPlotWidthPx) / std::max<size_t>(1, status.size());
  std::map<std::string, size_t> counts;
  for (size_t a = 0; a < status.size();) {
    size_t b = a;
    while (b < status.size() && status[b] == status[a]) ++b;
    counts[status[a]] += b - a;
    // Keyframes and lost frames are single frames among many: at least 1.5 px so they show.
    const double w = std::max(1.5, (b - a) * px_per_frame);
    s << "<rect class=\"datum\" x=\"" << fixed(kPlotLeftPx + a * px_per_frame, 2) << "\" y=\"" << top << "\" width=\""
      << fixed(w, 2) << "\" height=\"" << band_px << "\" fill=\"" << status_colour(status[a]) << "\"><title>frames "
      << a + 1 << "-" << b << ": " << html_escape(status[a]) << "</title></rect>";
    a = b;
  }
  int x = kPlotLeftPx;
  for (const char* name : {"tracking", "keyframe", "relocalised", "lost"}) {
    s << "<rect x=\"" << x << "\" y=\"" << legend_y - 10 << "\" width=\"12\" height=\"12\" fill=\"" << status_colour(name)
      << "\"/><text x=\"" << x + 16 << "\" y=\"" << legend_y << "\">" << name << " (" << counts[name] << ")</text>";
    x += 150;
  }
  s << "\n</svg>\n";
  return s.str();
}

/// A numeric column of report.json "frames" (null entries read `missing`).
std::vector<double> frame_column(const nlohmann::json& r, const char* key, double missing = 0.0) {
  std::vector<double> out;
  if (!r.contains("frames") || !r["frames"].contains(key)) return out;
  for (const auto& v : r["frames"][key]) out.push_back(v.is_number() ? v.get<double>() : missing);
  return out;
}

std::string ate_section(const nlohmann::json& r) {
  std::ostringstream h;
  h << "<h2>Trajectory error over time</h2>\n";
  std::vector<double> ate_cm = frame_column(r, "ate_m", std::numeric_limits<double>::quiet_NaN());
  const bool any = std::any_of(ate_cm.begin(), ate_cm.end(), [](double v) { return std::isfinite(v); });
  if (!any) {
    h << "<p class=\"missing\">"
      << (r.contains("tracking") ? "No ground-truth trajectory was compared: no trajectory error per frame."
                                 : "Poses were given, not estimated: there is no trajectory error to plot.")
      << "</p>\n";
    return h.str();
  }
  for (double& v : ate_cm) v *= 100.0;
  h << "<p class=\"explain\">Distance in centimetres between each estimated camera position and the "
       "ground truth, after the one rigid alignment of the whole trajectory (ATE). A rise is where the "
       "estimate drifted; a drop after a loop closure is the correction.</p>\n"
    << svg_series_chart({{"trajectory error (ATE)", "#9467bd", ate_cm}}, "cm");
  return h.str();
}

std::string per_frame_section(const nlohmann::json& r) {
  std::ostringstream h;
  h << "<h2>Time per frame</h2>\n";
  const std::vector<double> total = frame_column(r, "add_frame_ms"), tracking = frame_column(r, "tracking_ms");
  const double budget_ms = 1000.0 / kReportTargetFps;
  if (total.empty()) {
    h << "<p class=\"missing\">This report has no per-frame record, so there is no time or tracking plot "
         "per frame.</p>\n";
    return h.str();
  }
  h << "<p class=\"explain\">Milliseconds the mapper took to accept each frame (tracking plus handing the "
       "frame to fusion and segmentation; waiting on a full queue included) and the tracking part of it. "
       "Above the dashed line (the budget at "
    << fixed(kReportTargetFps, 0) << " fps) the mapper falls behind a live camera.</p>\n"
    << svg_series_chart({{"accepting the frame", "#4a7ab5", total}, {"tracking", "#e08a1e", tracking}}, "ms",
                        std::make_pair(budget_ms, "budget " + fixed(budget_ms, 1) + " ms"));
  h << "<h2>Tracking over time</h2>\n";
  std::vector<std::string> status;
  if (r["frames"].contains("status"))
    for (const auto& v : r["frames"]["status"]) status.push_back(v.is_string() ? v.get<std::string>() : "?");
  const std::vector<double> inliers = frame_column(r, "ransac_inliers");
  if (!r.contains("tracking")) {
    h << "<p class=\"missing\">Poses were given, not tracked: no tracking status or inlier count.</p>\n";
    return h.str();
  }
  h << "<p class=\"explain\">Status of each frame: tracked, made a new keyframe, lost (not fused into the map) "
       "or relocalised after a loss. Below: RANSAC inliers, the feature matches that agree with the estimated "
       "motion; few inliers is where tracking struggled.</p>\n"
    << svg_status_strip(status) << svg_series_chart({{"RANSAC inliers", "#2ca02c", inliers}}, "inliers");
  return h.str();
}

/// A stage's name as a person reads it (report.json keeps the key).
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
      once.push_back(stage_label(it.key()) + " " + (*mean >= 1000.0 ? fixed(*mean / 1000.0, 1) + " s" : fixed(*mean, 1) + " ms"));
      continue;
    }
    const auto p95 = number_at(*it, "p95_ms");
    bars.push_back({stage_label(it.key()), *mean, p95, "#4a7ab5",
                    fixed(*mean, 1) + " ms" + (p95 ? " (p95 " + fixed(*p95, 1) + ")" : "") + ", " + fixed(count, 0) +
                        " calls"});
  }
  if (bars.empty() && once.empty()) return h.str() + "<p class=\"missing\">No stage was timed in this run.</p>\n";
  const double budget_ms = 1000.0 / kReportTargetFps;
  h << "<p class=\"explain\">Bar: mean wall time of one call of each stage, in milliseconds; black tick: 95th "
       "percentile (the slow calls); dashed red line: the frame budget at "
    << fixed(kReportTargetFps, 0)
    << " fps. Stages on their own thread (segmentation, fusion, objects) overlap tracking; a stage slower than the "
       "budget falls behind a live camera or skips frames.</p>\n";
  if (!bars.empty())
    h << svg_bar_chart(bars, "ms", std::make_pair(budget_ms, "budget " + fixed(budget_ms, 1) + " ms"));
  if (!once.empty()) {
    h << "<p>Once, after the last frame: ";
    for (size_t i = 0; i < once.size(); ++i) h << (i ? ", " : "") << html_escape(once[i]);
    h << ".</p>\n";
  }
  return h.str();
}

std::string class_area_section(const nlohmann::json& r) {
  std::ostringstream h;
  h << "<h2>Labelled surface per class</h2>\n";
  const auto classes = r.contains("consistency") ? r["consistency"].value("class_area_share", nlohmann::json::object())
                                                 : nlohmann::json::object();
  std::vector<Bar> bars;
  for (auto it = classes.begin(); it != classes.end(); ++it) {
    if (!it->is_number()) continue;
    const double pct = it->get<double>() * 100.0;
    const auto id = class_from_name(it.key());
    bars.push_back({it.key(), pct, std::nullopt, id ? hex_colour(class_colour(*id)) : "#888", fixed(pct, 1) + " %"});
  }
  std::sort(bars.begin(), bars.end(), [](const Bar& a, const Bar& b) { return a.value > b.value; });
  if (bars.empty())
    return h.str() + "<p class=\"missing\">No surface carries a class label: the run had no semantic "
                     "segmentation, so there is no share per class.</p>\n";
  h << "<p class=\"explain\">Share of the mesh surface (by area, in percent of the whole mesh) that carries "
       "each class label.</p>\n"
    << svg_bar_chart(bars, "%");
  return h.str();
}

std::string objects_section(const nlohmann::json& r) {
  std::ostringstream h;
  h << "<h2>Objects per class</h2>\n";
  const nlohmann::json per_class = r.value("objects_per_class", nlohmann::json::object());
  std::vector<Bar> bars;
  for (auto it = per_class.begin(); it != per_class.end(); ++it) {
    if (!it->is_number()) continue;
    const auto id = class_from_name(it.key());
    bars.push_back({it.key(), it->get<double>(), std::nullopt, id ? hex_colour(class_colour(*id)) : "#888",
                    fixed(it->get<double>(), 0)});
  }
  std::sort(bars.begin(), bars.end(), [](const Bar& a, const Bar& b) { return a.value > b.value; });
  if (bars.empty()) return h.str() + "<p class=\"missing\">No object instance was kept in this run.</p>\n";
  h << "<p class=\"explain\">Number of object instances in the final map, per class (objects.json lists "
       "them with their boxes).</p>\n"
    << svg_bar_chart(bars, "objects");
  return h.str();
}

std::vector<Figure> quality_figures(const nlohmann::json& r) {
  const std::string no_gt = "no ground truth";
  std::vector<Figure> f = {
      {"Trajectory error (ATE RMSE)", value_or(r, "evaluation/ate/rmse_m", 100, 1, "cm", no_gt),
       "root mean square distance between estimated and ground-truth camera positions after alignment"},
      {"Trajectory error, worst pose", value_or(r, "evaluation/ate/max_m", 100, 1, "cm", no_gt),
       "the largest of those distances"},
      {"Drift (RPE)", value_or(r, "evaluation/rpe/trans_rmse_m_per_s", 100, 1, "cm/s", no_gt),
       "how fast the position error grows, per second of motion"},
      {"Labelled surface", value_or(r, "consistency/labelled_area_share", 100, 1, "%", "no labels"),
       "share of the mesh area that carries a class label"},
      {"Mesh area", value_or(r, "consistency/mesh_area_m2", 1, 1, "m²", "empty mesh"), "area of the mapped surface"},
      {"Floor facing up", value_or(r, "consistency/floor/facing_agreement", 100, 1, "%", "no floor labelled"),
       "share of floor-labelled area whose normal points up (within the agreement angle); low means mislabels"},
      {"Walls vertical", value_or(r, "consistency/wall/agreement", 100, 1, "%", "no wall labelled"),
       "share of wall-labelled area whose normal is horizontal"},
      {"Floor thickness", value_or(r, "consistency/floor_thickness_m", 100, 1, "cm", "no floor labelled"),
       "spread of floor heights; a thick floor means a doubled or tilted map"},
      {"Peak memory", value_or(r, "summary/peak_rss_mb", 1, 0, "MB", "not measured"),
       "largest resident memory of the process"},
      {"CPU time while streaming", value_or(r, "summary/cpu_s_online", 1, 1, "s", "not measured"),
       "processor time used until the last frame was read, all threads"},
      {"Keyframes", value_or(r, "summary/keyframes", 1, 0, "", "none"), "frames kept for relocalisation and loops"},
      {"Largest pose correction", value_or(r, "summary/max_pose_correction_m", 100, 1, "cm", "no correction"),
       "how far loop closure moved a keyframe; the map was rebuilt with the corrected poses"},
  };
  return f;
}

}  // namespace

void write_report_html(const std::filesystem::path& out_dir, const nlohmann::json& report,
                       const std::string& topdown_png, const std::vector<ObjectCard>& cards) {
  std::ostringstream h;
  h << "<!doctype html><html><head><meta charset=\"utf-8\"><title>semap report</title><style>"
       "body{font-family:sans-serif;margin:2em;max-width:1100px;color:#222}"
       "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:left}"
       "th{background:#eee}td.num{text-align:right;white-space:nowrap}p.summary{font-size:1.15em;line-height:1.5}"
       "p.explain{color:#555;font-size:.9em}p.missing{color:#8a5a00}img.map{max-width:100%;border:1px solid #ccc}"
       ".cards{display:flex;flex-wrap:wrap;gap:10px}.card{width:150px;border:1px solid #ccc;padding:6px;"
       "font-size:.85em}img.thumb{width:120px;height:120px;display:block;margin:auto}"
       "</style></head><body>\n";
  h << "<h1>semap run report</h1>\n";
  if (report.contains("dataset") && report["dataset"].is_string())
    h << "<p>Input: <code>" << html_escape(report["dataset"].get<std::string>()) << "</code></p>\n";
  h << summary_sentences(report);
  if (report.contains("evaluation") && report["evaluation"].contains("note"))
    if (report["evaluation"]["note"].is_string())
      h << "<p class=\"missing\">" << html_escape(report["evaluation"]["note"].get<std::string>()) << "</p>\n";
  const auto ate_max = number_at(report, "evaluation/ate/max_m");
  h << "<h2>Map from above</h2><p class=\"explain\">Labelled mesh seen from above (ceiling cut away), object "
       "footprints with class and id, and the camera path (black dot: start"
    << (ate_max ? "; coloured by trajectory error, green 0 cm to red " + fixed(*ate_max * 100, 1) + " cm"
                : "; no ground truth, so not coloured by error")
    << ").</p>" << png_img(topdown_png, "top-down view of the labelled map with object boxes and trajectory", "map") << "\n";
  h << per_frame_section(report) << ate_section(report) << timing_section(report) << class_area_section(report) << objects_section(report)
    << object_cards_section(cards);
  h << "<h2>Quality and cost</h2>\n" << figure_table(quality_figures(report));
  h << "<p class=\"explain\">Raw figures, with their machine-readable keys, are in report.json.</p>\n";
  h << "</body></html>\n";
  write_file_atomic(out_dir / "report.html", h.str());
}

}  // namespace semap
