// report.html (issue 43): a page a person reads after a run. A summary in sentences, plots
// drawn as inline SVG by semap (no script, no network, no CDN) and every figure with a readable
// name, a unit and a one-line explanation. Raw keys stay in report.json for scripts. The page
// is assembled here; its sections are in report_sections_*.cpp, the drawing in report_svg.cpp.
#include <cmath>
#include <sstream>

#include "core/paths.hpp"
#include "pipeline/report.hpp"
#include "pipeline/report_sections.hpp"
#include "pipeline/report_svg.hpp"

namespace semap {
namespace report {

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

std::string value_or(const nlohmann::json& r, const std::string& path, double scale, int decimals,
                     const std::string& unit, const std::string& missing) {
  const auto v = number_at(r, path);
  return v ? fixed(*v * scale, decimals) + (unit.empty() ? "" : " " + unit) : missing;
}

namespace {

constexpr const char* kStyle =
    "body{font-family:sans-serif;margin:2em;max-width:1100px;color:#222}"
    "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:left}"
    "th{background:#eee}td.num{text-align:right;white-space:nowrap}p.summary{font-size:1.15em;line-height:1.5}"
    "p.explain{color:#555;font-size:.9em}p.missing{color:#8a5a00}img.map,img.grid{max-width:100%;border:1px solid #ccc}"
    "img.grid{image-rendering:pixelated}.legend{font-size:.85em;line-height:2}.key{margin-right:14px;white-space:nowrap}"
    ".swatch{display:inline-block;width:12px;height:12px;border:1px solid #888;margin-right:4px;vertical-align:-2px}"
    ".path{display:inline-block;width:18px;height:3px;background:#1450c8;margin-right:4px;vertical-align:3px}"
    ".cards{display:flex;flex-wrap:wrap;gap:10px}.card{width:150px;border:1px solid #ccc;padding:6px;"
    "font-size:.85em}img.thumb{width:96px;height:96px;object-fit:contain;display:block;margin:auto}"
    ".note{color:#8a5a00;font-size:.9em}";

std::string header(const nlohmann::json& r) {
  std::string h = std::string("<!doctype html><html><head><meta charset=\"utf-8\"><title>semap report</title><style>") +
                  kStyle + "</style></head><body>\n<h1>semap run report</h1>\n";
  if (r.contains("dataset") && r["dataset"].is_string())
    h += "<p>Input: <code>" + html_escape(r["dataset"].get<std::string>()) + "</code></p>\n";
  h += summary_sentences(r);
  if (r.contains("evaluation") && r["evaluation"].is_object() && r["evaluation"].contains("note") &&
      r["evaluation"]["note"].is_string())
    h += "<p class=\"missing\">" + html_escape(r["evaluation"]["note"].get<std::string>()) + "</p>\n";
  return h;
}

}  // namespace
}  // namespace report

void write_report_html(const std::filesystem::path& out_dir, const nlohmann::json& r, const ReportPictures& pictures) {
  using namespace report;
  std::ostringstream h;
  h << header(r) << topdown_section(r, pictures.topdown_png) << grid_section(pictures.grid) << per_frame_section(r)
    << stage_frames_section(r) << ate_section(r) << timing_section(r) << class_area_section(r) << objects_section(r)
    << object_cards_section(pictures.cards) << quality_section(r) << "</body></html>\n";
  write_file_atomic(out_dir / "report.html", h.str());
}

}  // namespace semap
