#pragma once
// The sections of report.html (issue 43), each a function of the report.json document (and
// the pictures the run drew) returning its HTML. Pure functions: thread-safe. A section whose
// figure is missing says why in a sentence instead of drawing an empty plot.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/report.hpp"

namespace semap::report {

/// The frame budget drawn on the time plots: the 30 Hz of the RGB-D sensors semap reads
/// (TUM, 7-Scenes, Replica renders). A display reference, not a tuning parameter.
inline constexpr double kTargetFps = 30.0;

/// A finite number at `path` ("a/b/c") in `j`, or nullopt (missing, null, NaN, not a number).
std::optional<double> number_at(const nlohmann::json& j, const std::string& path);
/// value x scale + unit, or `missing` when the report has no finite number there.
std::string value_or(const nlohmann::json& r, const std::string& path, double scale, int decimals,
                     const std::string& unit, const std::string& missing);
/// A numeric column of report.json "frames" (null entries read `missing`).
std::vector<double> frame_column(const nlohmann::json& r, const char* key, double missing = 0.0);

// report_sections_run.cpp: how the run went.
std::string summary_sentences(const nlohmann::json& r);
std::string per_frame_section(const nlohmann::json& r);  ///< add_frame time, tracking status, inliers
std::string stage_frames_section(const nlohmann::json& r);  ///< per-frame time of every stage
std::string ate_section(const nlohmann::json& r);
std::string timing_section(const nlohmann::json& r);  ///< mean / p95 per stage
/// A stage's name as a person reads it (report.json keeps the key).
std::string stage_label(const std::string& key);

// report_sections_map.cpp: what was mapped.
std::string topdown_section(const nlohmann::json& r, const std::string& topdown_png);
std::string grid_section(const GridPicture& grid);
std::string class_area_section(const nlohmann::json& r);
std::string objects_section(const nlohmann::json& r);
std::string object_cards_section(const std::vector<ObjectCard>& cards);
std::string quality_section(const nlohmann::json& r);

}  // namespace semap::report
