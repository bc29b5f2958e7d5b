// Inline SVG plots of report.html (issue 43), see report_svg.hpp.
#include "pipeline/report_svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

namespace semap::report {

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

std::string hex_colour(Rgb8 c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c.r, c.g, c.b);
  return buf;
}

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

std::string inline_img(const std::string& bytes, const std::string& mime, const std::string& alt,
                       const std::string& css_class) {
  return "<img class=\"" + css_class + "\" src=\"data:" + mime + ";base64," + base64(bytes) + "\" alt=\"" +
         html_escape(alt) + "\">";
}

namespace {

std::string svg_open(int width_px, int height_px) {
  return "<svg class=\"plot\" width=\"" + std::to_string(width_px) + "\" height=\"" + std::to_string(height_px) +
         "\" font-size=\"12\" font-family=\"sans-serif\">\n";
}

/// Axis tick text: whole numbers (e.g. counts) as they are, others with two decimals below 1
/// and one below 100.
std::string tick(double v, double max_v) {
  if (v == std::floor(v) || max_v >= 100) return fixed(v, 0);
  return fixed(v, max_v < 1 ? 2 : 1);
}

}  // namespace

std::string svg_bar_chart(const std::vector<Bar>& bars, const std::string& unit, const std::optional<Reference>& reference) {
  const int row_px = 22, label_px = 230, plot_px = 480, value_px = 250, top_px = 24;
  double max_v = reference ? reference->value : 0.0;
  for (const Bar& b : bars) max_v = std::max({max_v, b.value, b.whisker.value_or(0.0)});
  if (max_v <= 0) max_v = 1;
  const auto x_of = [&](double v) { return label_px + plot_px * std::clamp(v / max_v, 0.0, 1.0); };
  const int bars_bottom = top_px + row_px * static_cast<int>(bars.size()) + 4;
  const int height = bars_bottom + (reference ? 18 : 4);  // the reference's caption below the bars
  std::ostringstream s;
  s << svg_open(label_px + plot_px + value_px, height);
  s << "<text x=\"" << label_px << "\" y=\"14\" fill=\"#555\">0</text><text x=\"" << label_px + plot_px
    << "\" y=\"14\" text-anchor=\"end\" fill=\"#555\">" << html_escape(tick(max_v, max_v) + " " + unit) << "</text>\n";
  const auto row_y = [&](size_t i) { return top_px + row_px * static_cast<int>(i); };
  const auto value_x = [&](const Bar& b) { return std::max(x_of(b.value), b.whisker ? x_of(*b.whisker) : 0.0) + 6; };
  for (size_t i = 0; i < bars.size(); ++i) {
    const Bar& b = bars[i];
    const int y = row_y(i);
    s << "<text x=\"" << label_px - 6 << "\" y=\"" << y + 14 << "\" text-anchor=\"end\">" << html_escape(b.label)
      << "</text>";
    s << "<rect class=\"datum\" x=\"" << label_px << "\" y=\"" << y + 3 << "\" width=\""
      << fixed(std::max(1.0, x_of(b.value) - label_px), 1) << "\" height=\"" << row_px - 6 << "\" fill=\"" << b.colour
      << "\"><title>" << html_escape(b.label + ": " + b.value_text) << "</title></rect>";
    if (b.whisker)
      s << "<line x1=\"" << fixed(x_of(*b.whisker), 1) << "\" x2=\"" << fixed(x_of(*b.whisker), 1) << "\" y1=\"" << y + 2
        << "\" y2=\"" << y + row_px - 2 << "\" stroke=\"#222\" stroke-width=\"2\"/>\n";
  }
  if (reference) {
    const double x = x_of(reference->value);
    s << "<line x1=\"" << fixed(x, 1) << "\" x2=\"" << fixed(x, 1) << "\" y1=\"18\" y2=\"" << bars_bottom
      << "\" stroke=\"#c0392b\" stroke-dasharray=\"5,3\"/><text x=\"" << fixed(x, 1) << "\" y=\"" << height - 3
      << "\" fill=\"#c0392b\">" << html_escape("- - " + reference->caption) << "</text>\n";
  }
  // The values last, with a white halo: readable where the reference line crosses them.
  for (size_t i = 0; i < bars.size(); ++i)
    s << "<text x=\"" << fixed(value_x(bars[i]), 1) << "\" y=\"" << row_y(i) + 14
      << "\" stroke=\"#fff\" stroke-width=\"4\" paint-order=\"stroke\">" << html_escape(bars[i].value_text)
      << "</text>\n";
  s << "</svg>\n";
  return s.str();
}

namespace {

constexpr int kPlotLeftPx = 60, kPlotWidthPx = 800, kPlotHeightPx = 160;

/// The points of one series over [x0, x0 + width): at most one per pixel column (the column's
/// largest finite value); frames without a value (NaN) give no point.
std::string polyline_points(const std::vector<double>& values, double x0, double width,
                            const std::function<double(double)>& y_of) {
  std::ostringstream s;
  const size_t columns = std::min<size_t>(values.size(), static_cast<size_t>(width));
  for (size_t c = 0; c < columns; ++c) {
    const size_t a = c * values.size() / columns, b = std::max(a + 1, (c + 1) * values.size() / columns);
    double v = std::numeric_limits<double>::quiet_NaN();
    for (size_t k = a; k < std::min(b, values.size()); ++k)
      if (std::isfinite(values[k]) && !(v >= values[k])) v = values[k];
    if (!std::isfinite(v)) continue;
    const double x = x0 + (columns > 1 ? width * static_cast<double>(c) / static_cast<double>(columns - 1) : 0.0);
    s << fixed(x, 1) << "," << fixed(y_of(v), 1) << " ";
  }
  return s.str();
}

std::string dashed_line(double x1, double x2, double y1, double y2) {
  return "<line x1=\"" + fixed(x1, 1) + "\" x2=\"" + fixed(x2, 1) + "\" y1=\"" + fixed(y1, 1) + "\" y2=\"" +
         fixed(y2, 1) + "\" stroke=\"#c0392b\" stroke-dasharray=\"5,3\"/>";
}

size_t longest(const std::vector<Series>& series) {
  size_t n = 0;
  for (const Series& l : series) n = std::max(n, l.values.size());
  return n;
}

std::string frame_axis(int y, size_t frames) {
  return "<text x=\"" + std::to_string(kPlotLeftPx) + "\" y=\"" + std::to_string(y) + "\">frame 1</text><text x=\"" +
         std::to_string(kPlotLeftPx + kPlotWidthPx) + "\" y=\"" + std::to_string(y) + "\" text-anchor=\"end\">frame " +
         std::to_string(frames) + "</text>\n";
}

}  // namespace

std::string svg_series_chart(const std::vector<Series>& series, const std::string& y_unit,
                             const std::optional<Reference>& reference) {
  double max_v = reference ? reference->value * 1.2 : 0.0;
  for (const Series& l : series)
    for (double v : l.values)
      if (std::isfinite(v)) max_v = std::max(max_v, v);
  if (max_v <= 0) max_v = 1;
  const int top = 22, legend_y = top + kPlotHeightPx + 34;
  const auto y_of = [&](double v) { return top + kPlotHeightPx * (1.0 - std::clamp(v / max_v, 0.0, 1.0)); };
  std::ostringstream s;
  s << svg_open(kPlotLeftPx + kPlotWidthPx + 20, legend_y + 10);
  s << "<rect x=\"" << kPlotLeftPx << "\" y=\"" << top << "\" width=\"" << kPlotWidthPx << "\" height=\"" << kPlotHeightPx
    << "\" fill=\"#fafafa\" stroke=\"#bbb\"/>\n";
  for (double f : {0.0, 0.5, 1.0})
    s << "<text x=\"" << kPlotLeftPx - 4 << "\" y=\"" << fixed(y_of(f * max_v) + 4, 1) << "\" text-anchor=\"end\">"
      << tick(f * max_v, max_v) << "</text>";
  s << "<text x=\"" << kPlotLeftPx << "\" y=\"" << top - 8 << "\" fill=\"#555\">" << html_escape(y_unit) << "</text>";
  s << frame_axis(top + kPlotHeightPx + 14, longest(series));
  int legend_x = kPlotLeftPx;
  for (const Series& l : series) {
    if (l.values.empty()) continue;
    s << "<polyline class=\"datum\" fill=\"none\" stroke=\"" << l.colour << "\" stroke-width=\"1.2\" points=\""
      << polyline_points(l.values, kPlotLeftPx, kPlotWidthPx, y_of) << "\"/>\n";
    s << "<rect x=\"" << legend_x << "\" y=\"" << legend_y - 9 << "\" width=\"14\" height=\"4\" fill=\"" << l.colour
      << "\"/><text x=\"" << legend_x + 18 << "\" y=\"" << legend_y << "\">" << html_escape(l.name) << "</text>\n";
    legend_x += 40 + 7 * static_cast<int>(l.name.size());
  }
  if (reference) {
    const double y = y_of(reference->value);
    s << dashed_line(kPlotLeftPx, kPlotLeftPx + kPlotWidthPx, y, y) << "<text x=\"" << legend_x << "\" y=\"" << legend_y
      << "\" fill=\"#c0392b\">- - " << html_escape(reference->caption) << "</text>\n";
  }
  s << "</svg>\n";
  return s.str();
}

std::string svg_series_strips(const std::vector<Series>& series, const std::string& y_unit,
                              const std::vector<double>& top_values, const std::optional<Reference>& reference) {
  const int strip_px = 46, gap_px = 10, label_px = 210, scale_px = 90, top = 6;
  const double plot_x = label_px, plot_w = kPlotLeftPx + kPlotWidthPx - label_px;
  const int height = top + static_cast<int>(series.size()) * (strip_px + gap_px) + 40;
  std::ostringstream s;
  s << svg_open(static_cast<int>(plot_x + plot_w) + scale_px, height);
  for (size_t i = 0; i < series.size(); ++i) {
    const Series& l = series[i];
    const double max_v = i < top_values.size() && top_values[i] > 0 ? top_values[i] : 1.0;
    const int y0 = top + static_cast<int>(i) * (strip_px + gap_px);
    const auto y_of = [&](double v) { return y0 + strip_px * (1.0 - std::clamp(v / max_v, 0.0, 1.0)); };
    s << "<rect x=\"" << plot_x << "\" y=\"" << y0 << "\" width=\"" << plot_w << "\" height=\"" << strip_px
      << "\" fill=\"#fafafa\" stroke=\"#bbb\"/><text x=\"" << label_px - 6 << "\" y=\"" << y0 + strip_px / 2 + 4
      << "\" text-anchor=\"end\">" << html_escape(l.name) << "</text>\n";
    s << "<text x=\"" << plot_x + plot_w + 4 << "\" y=\"" << y0 + 10 << "\" fill=\"#555\">" << html_escape(tick(max_v, max_v) + " " + y_unit)
      << "</text><text x=\"" << plot_x + plot_w + 4 << "\" y=\"" << y0 + strip_px << "\" fill=\"#555\">0</text>\n";
    s << "<polyline class=\"datum\" fill=\"none\" stroke=\"" << l.colour << "\" stroke-width=\"1.2\" points=\""
      << polyline_points(l.values, plot_x, plot_w, y_of) << "\"/>\n";
    if (reference && reference->value <= max_v)
      s << dashed_line(plot_x, plot_x + plot_w, y_of(reference->value), y_of(reference->value)) << "\n";
  }
  const int axis_y = top + static_cast<int>(series.size()) * (strip_px + gap_px) + 6;
  s << "<text x=\"" << label_px << "\" y=\"" << axis_y << "\">frame 1</text><text x=\"" << plot_x + plot_w << "\" y=\""
    << axis_y << "\" text-anchor=\"end\">frame " << longest(series) << "</text>\n";
  if (reference)
    s << "<text x=\"" << plot_x + plot_w << "\" y=\"" << axis_y + 20 << "\" text-anchor=\"end\" fill=\"#c0392b\">- - "
      << html_escape(reference->caption) << "</text>";
  s << "\n</svg>\n";
  return s.str();
}

namespace {

std::string status_colour(const std::string& status) {
  if (status == "keyframe") return "#2e6fbd";
  if (status == "lost") return "#d62728";
  if (status == "relocalised") return "#ff9f1a";
  return "#7fbf7f";  // tracking
}

}  // namespace

std::string svg_status_strip(const std::vector<std::string>& status) {
  const int top = 4, band_px = 26, legend_y = top + band_px + 18;
  std::ostringstream s;
  s << svg_open(kPlotLeftPx + kPlotWidthPx + 20, legend_y + 8);
  const double px_per_frame = static_cast<double>(kPlotWidthPx) / static_cast<double>(std::max<size_t>(1, status.size()));
  std::map<std::string, size_t> counts;
  for (size_t a = 0; a < status.size();) {
    size_t b = a;
    while (b < status.size() && status[b] == status[a]) ++b;
    counts[status[a]] += b - a;
    // Keyframes and lost frames are single frames among many: at least 1.5 px so they show.
    const double w = std::max(1.5, static_cast<double>(b - a) * px_per_frame);
    s << "<rect class=\"datum\" x=\"" << fixed(kPlotLeftPx + static_cast<double>(a) * px_per_frame, 2) << "\" y=\"" << top
      << "\" width=\"" << fixed(w, 2) << "\" height=\"" << band_px << "\" fill=\"" << status_colour(status[a])
      << "\"><title>frames " << a + 1 << "-" << b << ": " << html_escape(status[a]) << "</title></rect>";
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

}  // namespace semap::report
