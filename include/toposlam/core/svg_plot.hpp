// A small SVG line-plot writer for the figures of run folders (e.g. lambda2 over time with the place
// cuts, thesis Figure 4.10). Plain text output, no dependencies: axes with "nice" ticks, any number of
// line series (a NaN y value breaks the line), vertical dashed markers and horizontal reference lines.
// Stateless functions; thread-safe.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace toposlam {

struct SvgSeries {
  std::string label;      ///< shown in the legend when not empty
  std::vector<double> x;  ///< same length as y
  std::vector<double> y;  ///< NaN = gap in the line
  std::string colour = "#1f77b4";
  double stroke_width = 1.5;  ///< pixels
};

struct SvgLine {
  double value = 0.0;  ///< x (vertical line) or y (horizontal line) in data units
  std::string colour = "#555555";
  bool dashed = true;
  std::string label;  ///< optional text drawn beside the line
};

struct SvgPlot {
  std::string title;
  std::string x_label;
  std::string y_label;
  int width = 960;   ///< pixels
  int height = 360;  ///< pixels
  std::vector<SvgSeries> series;
  std::vector<SvgLine> vertical_lines;
  std::vector<SvgLine> horizontal_lines;
  std::optional<double> x_min, x_max, y_min, y_max;  ///< data range; derived from the data when empty
};

/// The whole SVG document. Never throws on odd data: empty plots, single points, NaN and infinite
/// values (skipped) all give a valid document.
std::string renderSvgLinePlot(const SvgPlot& plot);

/// About `target_count` round tick values (1, 2 or 5 times a power of ten) covering [low, high].
std::vector<double> niceTicks(double low, double high, int target_count = 6);

}  // namespace toposlam
