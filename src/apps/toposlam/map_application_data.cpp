// The application data of a map (see map_application_data.hpp for the formats).
#include "map_application_data.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace toposlam::cli {

namespace {

constexpr const char* kMapMagic = "toposlam-map-origins";
constexpr const char* kDaemonMagic = "toposlamd-frames";

/// A real number or "nan" (times in seconds, probabilities).
void writeTime(std::ostream& out, double t) {
  if (std::isnan(t))
    out << "nan";
  else
    out << t;
}

double readTime(std::istream& in) {
  std::string text;
  in >> text;
  if (text == "nan" || text.empty()) return std::numeric_limits<double>::quiet_NaN();
  try {
    return std::stod(text);
  } catch (const std::exception&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

void readPlaceLine(std::istringstream& line, MapApplicationData& data) {
  ObservationOrigin o;
  line >> o.run >> o.representative_frame >> o.first_frame >> o.last_frame;
  o.first_time_s = readTime(line);
  o.last_time_s = readTime(line);
  line >> o.keypoints >> o.end;
  if (o.end == "-") o.end.clear();
  if (!(line >> o.step_node)) o.step_node = -1;
  o.node_probability = readTime(line);
  o.best_topology_probability = readTime(line);
  o.effective_sample_size = readTime(line);
  data.origins.push_back(o);
}

void readRunLine(std::istringstream& line, MapApplicationData& data) {
  int run = -1;
  std::int64_t frames = 0;
  if (!(line >> run >> frames) || run < 0 || run > 100000 || frames < 0) return;
  const auto index = static_cast<std::size_t>(run);
  if (data.run_frames.size() <= index) data.run_frames.resize(index + 1, 0);
  data.run_frames[index] = frames;
}

void readTraversalLine(std::istringstream& line, MapApplicationData& data) {
  MapTraversal t;
  line >> t.run >> t.start_frame;
  t.start_time_s = readTime(line);
  std::getline(line >> std::ws, t.source);
  if (line.fail() && t.source.empty()) return;
  data.traversals.push_back(t);
}

/// Version 2: one record per line, by its first word.
void readVersion2(std::istream& in, MapApplicationData& data) {
  std::string text;
  while (std::getline(in, text)) {
    std::istringstream line(text);
    std::string kind;
    line >> kind;
    if (kind == "place")
      readPlaceLine(line, data);
    else if (kind == "run")
      readRunLine(line, data);
    else if (kind == "traversal")
      readTraversalLine(line, data);
  }
}

void readVersion1(std::istream& in, MapApplicationData& data) {
  ObservationOrigin o;
  while (in >> o.run >> o.representative_frame) data.origins.push_back(o);
}

}  // namespace

const char* writerName(MapApplicationData::Writer writer) {
  switch (writer) {
    case MapApplicationData::Writer::Map:
      return "toposlam map";
    case MapApplicationData::Writer::Daemon:
      return "toposlamd";
    case MapApplicationData::Writer::Unknown:
      break;
  }
  return "unknown";
}

std::string encodeMapApplicationData(const MapApplicationData& data) {
  std::ostringstream out;
  out << std::setprecision(std::numeric_limits<double>::max_digits10);
  out << kMapMagic << " 2\n";
  for (std::size_t r = 0; r < data.run_frames.size(); ++r) out << "run " << r << ' ' << data.run_frames[r] << '\n';
  for (const MapTraversal& t : data.traversals) {
    if (t.source.find_first_of("\r\n") != std::string::npos) continue;  // would break the line format
    out << "traversal " << t.run << ' ' << t.start_frame << ' ';
    writeTime(out, t.start_time_s);
    out << ' ' << t.source << '\n';
  }
  for (const ObservationOrigin& o : data.origins) {
    out << "place " << o.run << ' ' << o.representative_frame << ' ' << o.first_frame << ' ' << o.last_frame << ' ';
    writeTime(out, o.first_time_s);
    out << ' ';
    writeTime(out, o.last_time_s);
    out << ' ' << o.keypoints << ' ' << (o.end.empty() ? "-" : o.end) << ' ' << o.step_node;
    for (const double value : {o.node_probability, o.best_topology_probability, o.effective_sample_size}) {
      out << ' ';
      writeTime(out, value);
    }
    out << '\n';
  }
  return out.str();
}

MapApplicationData decodeMapApplicationData(const std::string& text, int observations) {
  std::istringstream in(text);
  std::string magic;
  int version = 0;
  MapApplicationData data;
  if (in >> magic && magic == kDaemonMagic) {
    data.writer = MapApplicationData::Writer::Daemon;
    ObservationOrigin o;
    while (in >> o.representative_frame) data.origins.push_back(o);
  } else if (magic == kMapMagic && in >> version) {
    data.writer = MapApplicationData::Writer::Map;
    if (version == 2) readVersion2(in, data);
    if (version == 1) readVersion1(in, data);
  }
  // A map written by another tool, or damaged bookkeeping: unknown origins.
  ObservationOrigin unknown;
  unknown.run = -1;
  data.origins.resize(static_cast<std::size_t>(std::max(observations, 0)), unknown);
  return data;
}

}  // namespace toposlam::cli
