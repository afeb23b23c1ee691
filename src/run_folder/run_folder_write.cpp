// The run folder's writers (see run_folder.hpp): every file through an OutputFile, so a full disk is an
// error naming the file and an earlier file of the same name is replaced whole or kept.
#include "toposlam/run_folder/run_folder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <system_error>

#include "toposlam/core/csv.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/platform/output_file.hpp"

namespace toposlam {

namespace fs = std::filesystem;

namespace {

std::string formatNumber(double value, int decimals) {
  char buffer[48];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

// A number with 6 decimals, or the empty field for NaN.
std::string optionalNumber(double value) { return std::isnan(value) ? std::string() : formatNumber(value, 6); }

std::int64_t nodeOf(const std::vector<std::int64_t>& place_nodes, std::int64_t place) {
  if (place < 0 || place >= static_cast<std::int64_t>(place_nodes.size())) return -1;
  return place_nodes[static_cast<std::size_t>(place)];
}

void writePlaceRows(const fs::path& path, const std::vector<PlaceRecord>& rows) {
  OutputFile out(path);
  out << "place,first,last,representative,keypoints,node,end\n";
  for (const PlaceRecord& p : rows)
    out << p.place << ',' << p.first << ',' << p.last << ',' << p.representative << ',' << p.keypoints << ','
        << p.node << ',' << quoteCsvField(p.end) << '\n';
  out.commit();
}

}  // namespace

void createRunFolder(const fs::path& dir) {
  std::error_code error;
  fs::create_directories(dir, error);
  if (error || !fs::is_directory(dir)) {
    throw std::runtime_error(dir.string() + ": cannot create the output folder" +
                             (error ? " (" + error.message() + ")" : std::string()));
  }
}

std::vector<FrameRecord> frameRows(const SegmentationRun& run, const std::vector<std::int64_t>& place_nodes) {
  std::vector<FrameRecord> rows;
  rows.reserve(run.frames.size());
  for (const SegmentationFrameRecord& f : run.frames) {
    FrameRecord row;
    row.frame = f.frame;
    row.time_s = f.time_s;
    row.name = f.name;
    if (f.lambda2) row.lambda2 = *f.lambda2;
    row.place = static_cast<int>(f.place);
    row.node = static_cast<int>(nodeOf(place_nodes, f.place));
    rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<PlaceRecord> placeRows(const std::vector<SegmentedPlace>& places,
                                   const std::vector<std::int64_t>& place_nodes) {
  std::vector<PlaceRecord> rows;
  rows.reserve(places.size());
  for (const SegmentedPlace& p : places) {
    PlaceRecord row;
    row.place = static_cast<int>(p.index);
    row.first = p.first_frame;
    row.last = p.last_frame;
    row.representative = p.representative_frame;
    row.keypoints = p.representative_keypoints;
    row.node = p.dropped ? -1 : static_cast<int>(nodeOf(place_nodes, p.index));
    row.end = placeEndName(p.end);
    rows.push_back(row);
  }
  return rows;
}

void writeFrames(const fs::path& dir, const std::vector<FrameRecord>& rows, FrameColumns columns) {
  const bool loop = columns == FrameColumns::WithLoopClosures;
  const bool probability = loop || columns == FrameColumns::WithNodeProbability;
  OutputFile out(dir / run_files::kFrames);
  out << "frame,time,name,lambda2,place,node" << (probability ? ",node_probability" : "")
      << (loop ? ",match,match_score" : "") << "\n";
  for (const FrameRecord& row : rows) {
    out << row.frame << ',' << formatNumber(row.time_s, 6) << ',' << quoteCsvField(row.name) << ','
        << optionalNumber(row.lambda2) << ',' << row.place << ',' << row.node;
    if (probability) out << ',' << optionalNumber(row.node_probability);
    if (loop) out << ',' << row.match << ',' << (row.match >= 0 ? formatNumber(row.match_score, 6) : std::string());
    out << '\n';
  }
  out.commit();
}

void writePlaces(const fs::path& dir, const std::vector<PlaceRecord>& rows) {
  writePlaceRows(dir / run_files::kPlaces, rows);
}

void writeDroppedPlaces(const fs::path& dir, const std::vector<PlaceRecord>& rows) {
  writePlaceRows(dir / run_files::kDroppedPlaces, rows);
}

void writeTopology(const fs::path& dir, const TopologyFile& topology) {
  OutputFile out(dir / run_files::kTopology);
  JsonWriter json(out);
  json.beginObject();
  json.field("probability", topology.probability);
  json.field("particles", topology.particles);
  if (const auto& e = topology.estimate) {
    json.field("current_node", e->current_node);
    json.field("current_node_probability", e->current_node_probability);
    json.field("effective_sample_size", e->effective_sample_size);
    json.field("distinct_topologies", e->distinct_topologies);
    json.field("earlier_places", e->earlier_places);
  }
  json.key("nodes").beginArray();
  for (const TopologyFile::Node& node : topology.nodes) {
    json.beginObject().field("id", node.id);
    json.key("places").beginArray();
    for (int p : node.places) json.value(p);
    json.endArray();
    json.key("representative_frames").beginArray();
    for (std::int64_t f : node.representative_frames) json.value(f);
    json.endArray();
    if (!node.earlier_places.empty()) {
      json.key("earlier_places").beginArray();
      for (int p : node.earlier_places) json.value(p);
      json.endArray();
    }
    json.endObject();
  }
  json.endArray();
  json.key("edges").beginArray();
  for (const TopologyFile::Edge& edge : topology.edges)
    json.beginObject().field("from", edge.from).field("to", edge.to).field("count", edge.count).endObject();
  json.endArray();
  if (topology.estimate) {
    json.key("alternatives").beginArray();
    for (const TopologyFile::Alternative& a : topology.estimate->alternatives) {
      json.beginObject().field("probability", a.probability).field("nodes", a.nodes);
      json.field("first_difference", a.first_difference).endObject();
    }
    json.endArray();
  }
  json.key("history").beginArray();
  for (const TopologyFile::Step& s : topology.history) {
    json.beginObject().field("place", s.place).field("node", s.node).field("probability", s.probability);
    if (s.best_topology_probability) json.field("best_topology_probability", *s.best_topology_probability);
    if (s.effective_sample_size) json.field("effective_sample_size", *s.effective_sample_size);
    if (s.is_new) json.field("is_new", *s.is_new);
    json.endObject();
  }
  json.endArray();
  json.endObject();
  out << "\n";
  out.commit();
}

void writeTiming(const fs::path& dir, const std::vector<TimingRow>& rows) {
  OutputFile out(dir / run_files::kTiming);
  out << "frame,fingerprint_ms,segment_ms,filter_ms\n";
  for (const TimingRow& row : rows) {
    char line[112];
    std::snprintf(line, sizeof(line), "%lld,%.4f,%.4f,", static_cast<long long>(row.frame), row.fingerprint_ms,
                  row.segment_ms);
    out << line;
    if (row.filter_ms) {
      std::snprintf(line, sizeof(line), "%.4f", *row.filter_ms);
      out << line;
    }
    out << '\n';
  }
  out.commit();
}

void writeSources(const fs::path& dir, const std::vector<std::string>& uris) {
  OutputFile out(dir / run_files::kSources);
  for (const std::string& uri : uris) out << uri << "\n";
  out.commit();
}

void writeSettings(const fs::path& dir, const RunSettings& settings) {
  OutputFile out(dir / run_files::kSettings);
  out << "# what this run was made with (toposlam map); read by toposlam report\n";
  for (const auto& [key, value] : settings) out << key << " = " << value << "\n";
  out.commit();
}

SvgPlot lambda2Plot(const SegmentationRun& run, const FiedlerSegmenterConfig& config, const std::string& title) {
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

void writeLambda2Plot(const fs::path& dir, const SegmentationRun& run, const FiedlerSegmenterConfig& config,
                      const std::string& title) {
  OutputFile out(dir / run_files::kLambda2Plot);
  out << renderSvgLinePlot(lambda2Plot(run, config, title));
  out.commit();
}

std::string labelsHeader() { return "frame,time,room,x,y,heading,traversal\n"; }

std::string labelsRow(const LabelRow& row) {
  char text[192];
  std::snprintf(text, sizeof text, "%lld,%.4f,%d,%.4f,%.4f,%.5f,%d\n", static_cast<long long>(row.frame), row.time_s,
                row.room, row.x, row.y, row.heading, row.traversal);
  return text;
}

}  // namespace toposlam
