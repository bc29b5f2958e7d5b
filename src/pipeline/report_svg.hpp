#pragma once
// The drawing kit of report.html (issue 43): HTML escaping, number formatting, embedded images
// and the inline SVG plots semap writes itself (no script, no network). Pure functions of their
// arguments: thread-safe. Every plot is an <svg class="plot"> whose data elements carry
// class="datum" (the report test checks that no plot is empty).
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "semap/core/labels.hpp"

namespace semap::report {

std::string html_escape(const std::string& s);
/// `v` with `decimals` digits after the point ("%.*f").
std::string fixed(double v, int decimals);
std::string hex_colour(Rgb8 c);
/// RFC 4648 base64, for the data: URIs that embed the images.
std::string base64(const std::string& bytes);
/// <img> with the encoded image inline; mime e.g. "image/png", "image/jpeg".
std::string inline_img(const std::string& bytes, const std::string& mime, const std::string& alt,
                       const std::string& css_class);

/// A dashed reference line on a plot (e.g. the frame budget) and its caption.
struct Reference {
  double value = 0.0;
  std::string caption;
};

/// One bar of a horizontal bar chart; `whisker` (same unit, >= value) draws a tick, e.g. p95.
struct Bar {
  std::string label;
  double value = 0;
  std::optional<double> whisker;
  std::string colour = "#4a7ab5";
  std::string value_text;
};

/// Horizontal bar chart: one row per bar, label left, value right of the bar, so labels never
/// overlap. `reference` draws a dashed vertical line.
std::string svg_bar_chart(const std::vector<Bar>& bars, const std::string& unit,
                          const std::optional<Reference>& reference = std::nullopt);

/// One line of a per-frame chart: one value per frame, NaN where the frame has none.
struct Series {
  std::string name, colour;
  std::vector<double> values;
};

/// Per-frame line chart: x = frame number, y from 0 to the largest value (or 1.2 x the
/// reference). Long runs are drawn with at most one point per pixel column (its maximum, so
/// spikes stay visible). Legend below the plot, so it covers no data.
std::string svg_series_chart(const std::vector<Series>& series, const std::string& y_unit,
                             const std::optional<Reference>& reference = std::nullopt);

/// Small multiples: one short strip per series over the same frame axis, its name left of it,
/// each on its own y scale from 0 to `top_values[i]` (printed right of the strip; values above
/// are clipped), the reference dashed in each strip that reaches it. For series of different
/// magnitudes whose lines would hide each other on one chart.
std::string svg_series_strips(const std::vector<Series>& series, const std::string& y_unit,
                              const std::vector<double>& top_values,
                              const std::optional<Reference>& reference = std::nullopt);

/// Tracking status over time: one coloured band (a run of equal statuses per rectangle) and a
/// legend with the count of each status.
std::string svg_status_strip(const std::vector<std::string>& status);

}  // namespace semap::report
