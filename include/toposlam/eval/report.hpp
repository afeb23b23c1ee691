// The one-page HTML report of a run folder (`toposlam report`): everything inline (SVG figures, JPEG
// thumbnails as base64 data URIs), so the file can be mailed or opened offline. Figures:
//   - a strip of frames coloured by node (or place), with the ground-truth rooms underneath when known,
//     and a grid of thumbnails with the same colours;
//   - lambda2 over time with the place cuts (thesis Figure 4.10);
//   - the most probable topology as a graph, each node drawn with a representative thumbnail (Figure 5.4);
//   - the probability of the most probable topology, and of the current node, after each place;
//   - processing time per frame (Figures 5.6/5.7);
//   - the evaluation tables and the loop-closure precision-recall curve.
// A small inline script writes `images-ok N` or `images-missing K` into #image-check once the page has
// loaded, for the headless-browser check (tests/apps/check_report_in_browser.sh).
//
// Thread-safety: pure functions of their inputs.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "toposlam/core/svg_plot.hpp"
#include "toposlam/eval/evaluation.hpp"

namespace toposlam::eval {

struct ReportInputs {
  std::string title;
  RunData run;
  std::optional<EvalResult> eval;
  std::vector<int> rooms;  ///< ground-truth room per frame, empty when unknown
  /// Per frame: a data URI ("data:image/jpeg;base64,...") of its thumbnail, or empty when not available.
  std::vector<std::string> thumbnails;
  std::vector<std::string> warnings;  ///< shown at the top (e.g. frames not found)
  std::string generator;              ///< what made the report ("toposlam 0.13.0"), shown in the header
  std::string generated;              ///< when (UTC date and time), shown in the header
  /// Pictures shown as they are (caption, data URI): the simulator's map.png and loop_closure.png.
  std::vector<std::pair<std::string, std::string>> pictures;
};

/// Frames worth a thumbnail: about `strip_count` evenly spaced frames plus every place's representative.
std::vector<std::int64_t> framesForThumbnails(const RunData& run, int strip_count);

std::string renderReportHtml(const ReportInputs& inputs);

/// Standard base64 (RFC 4648, with padding).
std::string base64Encode(const std::vector<std::uint8_t>& bytes);

/// One precision-recall curve of a plot.
struct PrSeries {
  std::string label;
  std::vector<PrPoint> points;
  std::string colour;
};
/// Precision (y) against recall (x), both in [0, 1], one line per curve (report, `toposlam recognition`).
SvgPlot precisionRecallPlot(const std::string& title, const std::vector<PrSeries>& curves);
/// A distinct, stable colour for index i (CSS "hsl(...)"); grey for i < 0.
std::string indexColour(int i);
/// The report's figures as standalone SVG documents by file name: strip.svg, rooms.svg (with labels),
/// lambda2.svg, topology.svg (thumbnails as <image> data URIs), probability.svg, timing.svg and
/// precision_recall.svg, each present only when the run/truth allows it.
std::map<std::string, std::string> renderReportFigures(const ReportInputs& inputs);

/// The topology as SVG + absolutely positioned <img> thumbnails inside one <div>.
std::string renderTopologyHtml(const RunData& run, const std::vector<std::string>& thumbnails);

}  // namespace toposlam::eval
