// The run-folder writers of an offline run's segmentation rows.
#include "toposlam/segmentation/offline_segmentation.hpp"

#include <cmath>
#include <cstdio>

namespace toposlam {

namespace {

std::string formatNumber(double value, int decimals) {
  char buffer[48];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

// A CSV field, quoted (quotes doubled) when it holds a comma, a quote or a line break.
std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::int64_t nodeOf(const std::vector<std::int64_t>& place_nodes, std::int64_t place) {
  if (place < 0 || place >= static_cast<std::int64_t>(place_nodes.size())) return -1;
  return place_nodes[static_cast<std::size_t>(place)];
}

}  // namespace

void writeFramesCsv(std::ostream& out, const SegmentationRun& run,
                    const std::vector<std::int64_t>& place_nodes, const FrameLoopColumns* loop) {
  out << "frame,time,name,lambda2,place,node" << (loop != nullptr ? ",node_probability,match,match_score" : "") << "\n";
  for (const SegmentationFrameRecord& row : run.frames) {
    out << row.frame << ',' << formatNumber(row.time_s, 6) << ',' << csvField(row.name) << ','
        << (row.lambda2 ? formatNumber(*row.lambda2, 6) : std::string()) << ',' << row.place << ','
        << nodeOf(place_nodes, row.place);
    if (loop != nullptr) {
      const auto f = static_cast<std::size_t>(row.frame);
      const bool placed = row.place >= 0 && static_cast<std::size_t>(row.place) < loop->place_probability.size();
      out << ',' << (placed ? formatNumber(loop->place_probability[static_cast<std::size_t>(row.place)], 6) : std::string())
          << ',' << (f < loop->match_frame.size() ? loop->match_frame[f] : -1) << ','
          << (f < loop->match_score.size() && loop->match_frame[f] >= 0 ? formatNumber(loop->match_score[f], 6) : std::string());
    }
    out << '\n';
  }
}

void writePlacesCsv(std::ostream& out, const std::vector<SegmentedPlace>& places,
                    const std::vector<std::int64_t>& place_nodes) {
  out << "place,first,last,representative,keypoints,node\n";
  for (const SegmentedPlace& p : places) {
    out << p.index << ',' << p.first_frame << ',' << p.last_frame << ',' << p.representative_frame << ','
        << p.representative_keypoints << ',' << (p.dropped ? -1 : nodeOf(place_nodes, p.index)) << '\n';
  }
}

SvgPlot lambda2Plot(const SegmentationRun& run, const FiedlerSegmenterConfig& config,
                    const std::string& title) {
  SvgPlot plot;
  plot.title = title;
  plot.x_label = "frame";
  plot.y_label = "algebraic connectivity (lambda2)";
  SvgSeries series;
  series.label = "lambda2, window " + std::to_string(config.window);
  for (const SegmentationFrameRecord& row : run.frames) {
    series.x.push_back(static_cast<double>(row.frame));
    series.y.push_back(row.lambda2 ? *row.lambda2 : std::nan(""));
  }
  plot.series.push_back(std::move(series));
  // A border is drawn between the last frame of a place and the first of the next.
  for (const SegmentedPlace& p : run.places) {
    if (p.valley_frame < 0) continue;  // closed by the end of the stream
    SvgLine line;
    line.value = static_cast<double>(p.last_frame) + 0.5;
    line.colour = "#d62728";
    plot.vertical_lines.push_back(line);
  }
  for (const SegmentedPlace& p : run.dropped_places) {
    if (p.valley_frame < 0) continue;
    SvgLine line;
    line.value = static_cast<double>(p.last_frame) + 0.5;
    line.colour = "#aaaaaa";
    plot.vertical_lines.push_back(line);
  }
  SvgLine gamma;
  gamma.value = config.valley.gamma;
  gamma.colour = "#2ca02c";
  gamma.label = "gamma " + formatNumber(config.valley.gamma, 2);
  plot.horizontal_lines.push_back(gamma);
  plot.y_min = 0.0;
  plot.y_max = std::max(maxFiedlerValue(config.window), 0.1) * 1.05;
  if (!run.frames.empty()) {
    plot.x_min = 0.0;
    plot.x_max = std::max(1.0, static_cast<double>(run.frames.size() - 1));
  }
  return plot;
}

}  // namespace toposlam
