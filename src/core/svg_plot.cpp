// SVG line plots: map data to the plot area, draw grid, ticks, series, markers, legend.
#include "toposlam/core/markup_escape.hpp"
#include "toposlam/core/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace toposlam {

namespace {

std::string number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.2f", value);
  return buffer;
}

std::string tickLabel(double value, double step) {
  const int decimals = step >= 1.0 ? 0 : std::min(6, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, std::abs(value) < step * 1e-9 ? 0.0 : value);
  return buffer;
}

struct Range {
  double low = std::numeric_limits<double>::infinity();
  double high = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    low = std::min(low, v);
    high = std::max(high, v);
  }
  void finish() {
    if (!std::isfinite(low)) {
      low = 0.0;
      high = 1.0;
    } else if (high - low <= 0.0) {
      const double pad = std::abs(low) > 0.0 ? 0.5 * std::abs(low) : 0.5;
      low -= pad;
      high += pad;
    }
  }
};

}  // namespace

std::vector<double> niceTicks(double low, double high, int target_count) {
  std::vector<double> ticks;
  if (!std::isfinite(low) || !std::isfinite(high) || high <= low || target_count < 1) return ticks;
  const double raw = (high - low) / target_count;
  const int exponent = static_cast<int>(std::floor(std::log10(raw)));
  // Tick k is k * factor * 10^exponent; for negative exponents divide by 10^-exponent so that e.g.
  // 3 * 2 / 10 is exactly the double nearest 0.6.
  const double scale = std::pow(10.0, std::abs(exponent));
  auto at = [&](double units) { return exponent < 0 ? units / scale : units * scale; };
  double factor = 1.0;
  for (double candidate : {1.0, 2.0, 5.0, 10.0}) {
    factor = candidate;
    if (at(candidate) >= raw) break;
  }
  const double step = at(factor);
  const double first = std::ceil(low / step - 1e-9);
  for (double k = first; at(k * factor) <= high + step * 1e-9; k += 1.0) {
    ticks.push_back(k == 0.0 ? 0.0 : at(k * factor));
    if (ticks.size() > 1000) break;
  }
  return ticks;
}

std::string renderSvgLinePlot(const SvgPlot& plot) {
  const int width = std::max(plot.width, 200);
  const int height = std::max(plot.height, 150);
  const double left = 64, right = 16, top = plot.title.empty() ? 16 : 36, bottom = 48;
  const double area_w = width - left - right;
  const double area_h = height - top - bottom;

  Range xr, yr;
  for (const SvgSeries& s : plot.series) {
    const std::size_t n = std::min(s.x.size(), s.y.size());
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      xr.add(s.x[i]);
      yr.add(s.y[i]);
    }
  }
  for (const SvgLine& l : plot.horizontal_lines) yr.add(l.value);
  if (plot.x_min) xr.low = *plot.x_min;
  if (plot.x_max) xr.high = *plot.x_max;
  if (plot.y_min) yr.low = *plot.y_min;
  if (plot.y_max) yr.high = *plot.y_max;
  xr.finish();
  yr.finish();

  auto px = [&](double x) { return left + (x - xr.low) / (xr.high - xr.low) * area_w; };
  auto py = [&](double y) { return top + (1.0 - (y - yr.low) / (yr.high - yr.low)) * area_h; };
  auto inside_x = [&](double x) { return std::isfinite(x) && x >= xr.low && x <= xr.high; };
  auto inside_y = [&](double y) { return std::isfinite(y) && y >= yr.low && y <= yr.high; };

  std::ostringstream svg;
  svg << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" viewBox=\"0 0 " << width << " " << height << "\" font-family=\"sans-serif\" font-size=\"11\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  if (!plot.title.empty()) {
    svg << "<text x=\"" << number(width / 2.0) << "\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">"
        << escapeMarkup(plot.title) << "</text>\n";
  }

  // Grid and ticks.
  const std::vector<double> xticks = niceTicks(xr.low, xr.high, std::max(2, static_cast<int>(area_w / 90)));
  const std::vector<double> yticks = niceTicks(yr.low, yr.high, std::max(2, static_cast<int>(area_h / 50)));
  const double xstep = xticks.size() > 1 ? xticks[1] - xticks[0] : 1.0;
  const double ystep = yticks.size() > 1 ? yticks[1] - yticks[0] : 1.0;
  svg << "<g stroke=\"#e5e5e5\" stroke-width=\"1\">\n";
  for (double t : xticks) {
    svg << "<line x1=\"" << number(px(t)) << "\" y1=\"" << number(top) << "\" x2=\"" << number(px(t))
        << "\" y2=\"" << number(top + area_h) << "\"/>\n";
  }
  for (double t : yticks) {
    svg << "<line x1=\"" << number(left) << "\" y1=\"" << number(py(t)) << "\" x2=\"" << number(left + area_w)
        << "\" y2=\"" << number(py(t)) << "\"/>\n";
  }
  svg << "</g>\n<g fill=\"#333333\">\n";
  for (double t : xticks) {
    svg << "<text x=\"" << number(px(t)) << "\" y=\"" << number(top + area_h + 16)
        << "\" text-anchor=\"middle\">" << tickLabel(t, xstep) << "</text>\n";
  }
  for (double t : yticks) {
    svg << "<text x=\"" << number(left - 6) << "\" y=\"" << number(py(t) + 4) << "\" text-anchor=\"end\">"
        << tickLabel(t, ystep) << "</text>\n";
  }
  svg << "</g>\n";
  svg << "<rect x=\"" << number(left) << "\" y=\"" << number(top) << "\" width=\"" << number(area_w)
      << "\" height=\"" << number(area_h) << "\" fill=\"none\" stroke=\"#333333\"/>\n";
  if (!plot.x_label.empty()) {
    svg << "<text x=\"" << number(left + area_w / 2) << "\" y=\"" << number(height - 10.0)
        << "\" text-anchor=\"middle\">" << escapeMarkup(plot.x_label) << "</text>\n";
  }
  if (!plot.y_label.empty()) {
    svg << "<text transform=\"translate(16 " << number(top + area_h / 2)
        << ") rotate(-90)\" text-anchor=\"middle\">" << escapeMarkup(plot.y_label) << "</text>\n";
  }

  // Reference lines.
  for (const SvgLine& l : plot.horizontal_lines) {
    if (!inside_y(l.value)) continue;
    svg << "<line x1=\"" << number(left) << "\" y1=\"" << number(py(l.value)) << "\" x2=\""
        << number(left + area_w) << "\" y2=\"" << number(py(l.value)) << "\" stroke=\"" << escapeMarkup(l.colour)
        << "\" stroke-width=\"1\"" << (l.dashed ? " stroke-dasharray=\"6 4\"" : "") << "/>\n";
    if (!l.label.empty()) {
      svg << "<text x=\"" << number(left + area_w - 4) << "\" y=\"" << number(py(l.value) - 3)
          << "\" text-anchor=\"end\" fill=\"" << escapeMarkup(l.colour) << "\">" << escapeMarkup(l.label)
          << "</text>\n";
    }
  }
  for (const SvgLine& l : plot.vertical_lines) {
    if (!inside_x(l.value)) continue;
    svg << "<line x1=\"" << number(px(l.value)) << "\" y1=\"" << number(top) << "\" x2=\""
        << number(px(l.value)) << "\" y2=\"" << number(top + area_h) << "\" stroke=\"" << escapeMarkup(l.colour)
        << "\" stroke-width=\"1\"" << (l.dashed ? " stroke-dasharray=\"6 4\"" : "") << "/>\n";
    if (!l.label.empty()) {
      svg << "<text x=\"" << number(px(l.value) + 3) << "\" y=\"" << number(top + 11) << "\" fill=\""
          << escapeMarkup(l.colour) << "\">" << escapeMarkup(l.label) << "</text>\n";
    }
  }

  // Series: one polyline per run of finite points.
  for (const SvgSeries& s : plot.series) {
    const std::size_t n = std::min(s.x.size(), s.y.size());
    std::ostringstream points;
    std::size_t in_run = 0;
    auto flush_run = [&] {
      if (in_run > 0) {
        svg << "<polyline fill=\"none\" stroke=\"" << escapeMarkup(s.colour) << "\" stroke-width=\""
            << number(s.stroke_width) << "\" points=\"" << points.str() << "\"/>\n";
      }
      points.str("");
      in_run = 0;
    };
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        flush_run();
        continue;
      }
      const double x = std::clamp(px(s.x[i]), left, left + area_w);
      const double y = std::clamp(py(s.y[i]), top, top + area_h);
      points << (in_run > 0 ? " " : "") << number(x) << "," << number(y);
      ++in_run;
    }
    flush_run();
  }

  // Legend, top right.
  double legend_y = top + 14;
  for (const SvgSeries& s : plot.series) {
    if (s.label.empty()) continue;
    const double x = left + area_w - 150;
    svg << "<line x1=\"" << number(x) << "\" y1=\"" << number(legend_y - 4) << "\" x2=\"" << number(x + 20)
        << "\" y2=\"" << number(legend_y - 4) << "\" stroke=\"" << escapeMarkup(s.colour)
        << "\" stroke-width=\"2\"/>\n"
        << "<text x=\"" << number(x + 26) << "\" y=\"" << number(legend_y) << "\">" << escapeMarkup(s.label)
        << "</text>\n";
    legend_y += 16;
  }
  svg << "</svg>\n";
  return svg.str();
}

}  // namespace toposlam
