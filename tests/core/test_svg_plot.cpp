// The SVG line-plot helper (core/svg_plot): valid documents for ordinary and odd data, nice ticks.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "toposlam/core/svg_plot.hpp"

namespace {
std::size_t countOf(const std::string& text, const std::string& what) {
  std::size_t count = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++count;
  return count;
}
}  // namespace

TEST_CASE("GIVEN a range WHEN nice ticks are chosen THEN they are round and cover it", "[core][svg]") {
  CHECK(toposlam::niceTicks(0.0, 1.0, 5) == std::vector<double>{0.0, 0.2, 0.4, 0.6, 0.8, 1.0});
  CHECK(toposlam::niceTicks(0.0, 100.0, 4) == std::vector<double>{0.0, 50.0, 100.0});
  CHECK(toposlam::niceTicks(3.0, 17.0, 3) == std::vector<double>{5.0, 10.0, 15.0});
  CHECK(toposlam::niceTicks(1.0, 1.0).empty());
  CHECK(toposlam::niceTicks(NAN, 1.0).empty());
}

TEST_CASE(
    "GIVEN a series with a gap and two dashed markers WHEN rendered THEN the SVG has two polylines and two "
    "dashed lines",
    "[core][svg]") {
  toposlam::SvgPlot plot;
  plot.title = "lambda2 <cuts>";
  toposlam::SvgSeries series;
  series.label = "lambda2";
  series.x = {0, 1, 2, 3, 4};
  series.y = {0.1, 0.5, NAN, 0.9, 1.0};
  plot.series.push_back(series);
  for (double x : {1.5, 3.5, 99.0}) {  // 99 is outside the x range: not drawn
    toposlam::SvgLine line;
    line.value = x;
    plot.vertical_lines.push_back(line);
  }
  const std::string svg = toposlam::renderSvgLinePlot(plot);
  CHECK(svg.rfind("<?xml", 0) == 0);
  CHECK(svg.find("</svg>") != std::string::npos);
  CHECK(countOf(svg, "<polyline") == 2);
  CHECK(countOf(svg, "stroke-dasharray") == 2);
  CHECK(svg.find("lambda2 &lt;cuts&gt;") != std::string::npos);
}

TEST_CASE("GIVEN no data WHEN rendered THEN the document is still valid", "[core][svg]") {
  const std::string svg = toposlam::renderSvgLinePlot({});
  CHECK(svg.find("<svg") != std::string::npos);
  CHECK(svg.find("</svg>") != std::string::npos);
  CHECK(countOf(svg, "<polyline") == 0);
  CHECK(svg.find("nan") == std::string::npos);
}
