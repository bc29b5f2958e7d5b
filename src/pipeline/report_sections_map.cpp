// report.html sections on what was mapped (issues 43, 39): the top-down picture, the
// occupancy grid, labelled surface and objects per class, object cards, quality figures.
#include <algorithm>
#include <array>
#include <functional>
#include <sstream>

#include "pipeline/report_sections.hpp"
#include "pipeline/report_svg.hpp"

namespace semap::report {

std::string topdown_section(const nlohmann::json& r, const std::string& topdown_png) {
  const auto ate_max = number_at(r, "evaluation/ate/max_m");
  return "<h2>Map from above</h2><p class=\"explain\">Labelled mesh seen from above (ceiling cut away), object "
         "footprints with class and id, and the camera path (black dot: start" +
         (ate_max ? "; coloured by trajectory error, green 0 cm to red " + fixed(*ate_max * 100, 1) + " cm"
                  : std::string("; no ground truth, so not coloured by error")) +
         ").</p>" +
         inline_img(topdown_png, "image/png", "top-down view of the labelled map with object boxes and trajectory", "map") +
         "\n";
}

namespace {

std::string swatch(const std::string& colour, const std::string& name) {
  return "<span class=\"key\"><span class=\"swatch\" style=\"background:" + colour + "\"></span>" + html_escape(name) +
         "</span>";
}

std::string grid_legend(const GridPicture& grid) {
  const auto cells = [](size_t n) { return " (" + std::to_string(n) + " cells)"; };
  std::string h = "<div class=\"legend\">" + swatch("#ffffff", "free" + cells(grid.free_cells)) +
                  swatch("#cdcdcd", "unknown" + cells(grid.unknown_cells)) +
                  swatch("#000000", "occupied, unlabelled") +
                  "<span class=\"key\"><span class=\"path\"></span>camera path (black dot: start)</span>";
  if (!grid.classes.empty()) h += "<br>occupied, by the class of its top surface: ";
  for (ClassId c : grid.classes) h += swatch(hex_colour(class_colour(c)), std::string(class_name(c)));
  return h + "</div>\n";
}

}  // namespace

std::string grid_section(const GridPicture& grid) {
  std::ostringstream h;
  h << "<h2>Where a robot can drive</h2>\n";
  if (grid.png.empty())
    return h.str() + "<p class=\"missing\">No occupancy grid: nothing was mapped at floor level or in the robot's "
                     "height band.</p>\n";
  h << "<p class=\"explain\">The occupancy grid of map.pgm, seen from above in the gravity frame (up in the picture is its +y): "
       "a cell is occupied where the map has a surface in the robot's height band (navigation.min_height_m to "
       "max_height_m), free where the floor was seen with nothing above it in the band, unknown elsewhere. "
    << grid.width_cells << " x " << grid.height_cells << " cells of " << fixed(grid.resolution_m * 100, 1)
    << " cm; " << grid.occupied_cells << " occupied. map_labels.png has each cell's class.</p>\n"
    << inline_img(grid.png, "image/png", "occupancy grid with the camera path", "grid") << "\n"
    << grid_legend(grid);
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
    const std::string text = pct > 0 && pct < 0.05 ? "< 0.1 %" : fixed(pct, 1) + " %";  // not "0.0 %" for a sliver
    bars.push_back({it.key(), pct, std::nullopt, id ? hex_colour(class_colour(*id)) : "#888", text});
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

namespace {

std::string object_card(const ObjectCard& c) {
  std::array<double, 3> size{c.size_m.x(), c.size_m.y(), c.size_m.z()};
  std::sort(size.begin(), size.end(), std::greater<>());
  const bool crop = c.thumbnail_source == ThumbnailSource::camera_crop;
  return "<div class=\"card\">" +
         inline_img(c.thumbnail, c.thumbnail_mime, c.class_name + " " + std::to_string(c.id), crop ? "thumb" : "thumb voxels") +
         "<div><b>" + html_escape(c.class_name) + "</b> #" + std::to_string(c.id) + "</div><div>confidence " +
         fixed(c.confidence * 100, 0) + " %</div><div>" + fixed(size[0], 2) + " x " + fixed(size[1], 2) + " x " +
         fixed(size[2], 2) + " m</div>" + (crop ? "" : "<div class=\"note\">drawn from its voxels</div>") + "</div>\n";
}

}  // namespace

std::string object_cards_section(const std::vector<ObjectCard>& cards) {
  std::string h = "<h2>Objects</h2>\n";
  if (cards.empty()) return h + "<p class=\"missing\">No object instance was kept in this run.</p>\n";
  h += "<p class=\"explain\">Each object of the final map: class, detector confidence (mean score of the "
       "detections merged into it, 0-100 %), size of its box in metres (longest side first), and a crop of the "
       "keyframe that saw it best (largest unoccluded view of it); an object no kept keyframe showed (e.g. from a "
       "map saved by an older semap) is drawn from its coloured voxels instead.</p>\n<div class=\"cards\">\n";
  for (const ObjectCard& c : cards) h += object_card(c);
  return h + "</div>\n";
}

namespace {

/// A readable figure: name, value with unit, one-line explanation. Missing values say why.
struct Figure {
  std::string name, value, explanation;
};

/// Why the evaluation left RPE out (report.json evaluation.rpe.reason, e.g. a recording shorter
/// than its 1 s step), as a clause of the figure's explanation; empty when computed or no ground truth.
std::string rpe_missing_reason(const nlohmann::json& r) {
  const nlohmann::json::json_pointer at("/evaluation/rpe/reason");
  return r.contains(at) && r.at(at).is_string() ? "; not computed here: " + r.at(at).get<std::string>() : "";
}

std::vector<Figure> quality_figures(const nlohmann::json& r) {
  const std::string no_gt = "no ground truth";
  const std::string rpe_reason = rpe_missing_reason(r);
  return {
      {"Trajectory error (ATE RMSE)", value_or(r, "evaluation/ate/rmse_m", 100, 1, "cm", no_gt),
       "root mean square distance between estimated and ground-truth camera positions after alignment"},
      {"Trajectory error, worst pose", value_or(r, "evaluation/ate/max_m", 100, 1, "cm", no_gt),
       "the largest of those distances"},
      {"Drift (RPE)", value_or(r, "evaluation/rpe/trans_rmse_m_per_s", 100, 1, "cm/s", rpe_reason.empty() ? no_gt : "not computed"),
       "how fast the position error grows, per second of motion" + rpe_reason},
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
}

}  // namespace

std::string quality_section(const nlohmann::json& r) {
  std::ostringstream s;
  s << "<h2>Quality and cost</h2>\n<table class=\"figures\"><tr><th>figure</th><th>value</th><th>what it means</th></tr>\n";
  for (const Figure& f : quality_figures(r))
    s << "<tr><td>" << html_escape(f.name) << "</td><td class=\"num\">" << html_escape(f.value) << "</td><td>"
      << html_escape(f.explanation) << "</td></tr>\n";
  s << "</table>\n<p class=\"explain\">Raw figures, with their machine-readable keys, are in report.json.</p>\n";
  return s.str();
}

}  // namespace semap::report
