// The run folder's readers (see run_folder.hpp). All errors name file and line.
#include "toposlam/run_folder/run_folder.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "toposlam/core/csv.hpp"
#include "toposlam/run_folder/json_reader.hpp"

namespace toposlam {

namespace fs = std::filesystem;

namespace {

std::string where(const CsvTable& t, std::size_t row) { return t.path + ":" + std::to_string(t.lines[row]); }

/// places.csv's `end`: one of placeEndName's values.
bool isPlaceEndName(const std::string& name) {
  for (PlaceEnd e : {PlaceEnd::Valley, PlaceEnd::ValleyAtDoorway, PlaceEnd::DoorwayPassage,
                     PlaceEnd::InterruptedValley, PlaceEnd::StreamEnd}) {
    if (name == placeEndName(e)) return true;
  }
  return false;
}

}  // namespace

CsvTable readCsv(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RunFileError(path + ": cannot open (does the file exist?)");
  CsvTable table;
  table.path = path;
  CsvReader reader(in);
  for (CsvRecord record; reader.next(record);) {
    if (!record.problem.empty()) throw RunFileError(path + ":" + std::to_string(record.line) + ": " + record.problem);
    std::vector<std::string> cells = std::move(record.fields);
    if (table.header.empty()) {
      table.header = std::move(cells);
      continue;
    }
    if (cells.size() < table.header.size()) cells.resize(table.header.size());  // tolerate trailing empties
    table.rows.push_back(std::move(cells));
    table.lines.push_back(record.line);
  }
  if (table.header.empty()) throw RunFileError(path + ":1: empty file, expected a header line");
  return table;
}

int CsvTable::column(const std::string& name, bool required) const {
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (header[i] == name) return static_cast<int>(i);
  }
  if (required) {
    std::string have;
    for (const auto& h : header) have += (have.empty() ? "" : ",") + h;
    throw RunFileError(path + ":1: missing column '" + name + "' (header is: " + have + ")");
  }
  return -1;
}

double CsvTable::number(std::size_t row, int col, bool allow_empty) const {
  const std::string& text = rows[row][static_cast<std::size_t>(col)];
  if (text.empty()) {
    if (allow_empty) return std::nan("");
    throw RunFileError(where(*this, row) + ": column '" + header[static_cast<std::size_t>(col)] +
                       "' is empty");
  }
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0') {
    throw RunFileError(where(*this, row) + ": column '" + header[static_cast<std::size_t>(col)] + "': '" +
                       text + "' is not a number");
  }
  return v;
}

std::int64_t CsvTable::integer(std::size_t row, int col) const {
  const double v = number(row, col);
  if (v != std::floor(v) || std::abs(v) > 9e15) {
    throw RunFileError(where(*this, row) + ": column '" + header[static_cast<std::size_t>(col)] + "': '" +
                       rows[row][static_cast<std::size_t>(col)] + "' is not an integer");
  }
  return static_cast<std::int64_t>(v);
}

std::vector<LabelRow> loadLabels(const std::string& path) {
  const CsvTable t = readCsv(path);
  const int frame = t.column("frame"), room = t.column("room"), time = t.column("time", false),
            traversal = t.column("traversal", false);
  const int x = t.column("x", false), y = t.column("y", false), heading = t.column("heading", false);
  const bool has_pose = x >= 0 || y >= 0 || heading >= 0;
  if (has_pose && (x < 0 || y < 0 || heading < 0))
    throw RunFileError(path + ":1: a pose needs all of the columns x, y and heading (found " +
                       std::string(x >= 0 ? "x " : "") + (y >= 0 ? "y " : "") + (heading >= 0 ? "heading" : "") + ")");
  std::vector<LabelRow> rows;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    LabelRow row;
    row.frame = t.integer(r, frame);
    row.room = static_cast<int>(t.integer(r, room));
    row.time_s = time >= 0 ? t.number(r, time, true) : 0.0;
    if (row.frame != static_cast<std::int64_t>(rows.size())) {
      throw RunFileError(where(t, r) + ": frame " + std::to_string(row.frame) + " out of order, expected " +
                         std::to_string(rows.size()));
    }
    if (row.room < -1)
      throw RunFileError(where(t, r) + ": room " + std::to_string(row.room) + " must be >= -1");
    if (traversal >= 0) {
      row.traversal = static_cast<int>(t.integer(r, traversal));
      const int previous = rows.empty() ? 0 : rows.back().traversal;
      if (row.traversal < previous) {
        throw RunFileError(where(t, r) + ": traversal " + std::to_string(row.traversal) +
                           " after traversal " + std::to_string(previous) +
                           " (must be >= 0 and never decrease)");
      }
    }
    if (has_pose) {
      row.x = t.number(r, x);
      row.y = t.number(r, y);
      row.heading = t.number(r, heading);
      if (!std::isfinite(row.x) || !std::isfinite(row.y) || !std::isfinite(row.heading))
        throw RunFileError(where(t, r) + ": the pose (x, y, heading) must be finite numbers");
    }
    rows.push_back(row);
  }
  return rows;
}

std::vector<FrameRecord> loadFrames(const std::string& path) {
  const CsvTable t = readCsv(path);
  const int frame = t.column("frame"), time = t.column("time", false), name = t.column("name", false),
            lambda2 = t.column("lambda2", false), place = t.column("place"), node = t.column("node", false),
            node_probability = t.column("node_probability", false), match = t.column("match", false),
            match_score = t.column("match_score", false);
  std::vector<FrameRecord> rows;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    FrameRecord row;
    row.frame = t.integer(r, frame);
    if (row.frame != static_cast<std::int64_t>(rows.size())) {
      throw RunFileError(where(t, r) + ": frame " + std::to_string(row.frame) + " out of order, expected " +
                         std::to_string(rows.size()));
    }
    if (time >= 0) row.time_s = t.number(r, time, true);
    if (name >= 0) row.name = t.rows[r][static_cast<std::size_t>(name)];
    if (lambda2 >= 0) row.lambda2 = t.number(r, lambda2, true);
    row.place = static_cast<int>(t.integer(r, place));
    row.node = node >= 0 && !t.rows[r][static_cast<std::size_t>(node)].empty()
                   ? static_cast<int>(t.integer(r, node))
                   : -1;
    if (node_probability >= 0) row.node_probability = t.number(r, node_probability, true);
    if (match >= 0 && !t.rows[r][static_cast<std::size_t>(match)].empty()) row.match = t.integer(r, match);
    if (match_score >= 0) {
      row.match_score = t.number(r, match_score, true);
      if (std::isnan(row.match_score)) row.match_score = 0.0;
    }
    if (row.match >= row.frame)
      throw RunFileError(where(t, r) + ": match " + std::to_string(row.match) + " is not an earlier frame");
    rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<PlaceRecord> loadPlaces(const std::string& path) {
  const CsvTable t = readCsv(path);
  const int place = t.column("place"), first = t.column("first"), last = t.column("last"),
            rep = t.column("representative"), kp = t.column("keypoints", false),
            node = t.column("node", false), end = t.column("end", false);
  std::vector<PlaceRecord> rows;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    PlaceRecord row;
    row.line = t.lines[r];
    row.place = static_cast<int>(t.integer(r, place));
    row.first = t.integer(r, first);
    row.last = t.integer(r, last);
    row.representative = t.integer(r, rep);
    if (kp >= 0) row.keypoints = static_cast<int>(t.integer(r, kp));
    row.node = node >= 0 && !t.rows[r][static_cast<std::size_t>(node)].empty()
                   ? static_cast<int>(t.integer(r, node))
                   : -1;
    if (end >= 0) {
      row.end = t.rows[r][static_cast<std::size_t>(end)];
      if (!row.end.empty() && !isPlaceEndName(row.end)) {
        throw RunFileError(where(t, r) + ": end '" + row.end +
                           "' is not one of valley, valley_at_doorway, doorway, interrupted_valley, "
                           "stream_end (or empty)");
      }
    }
    if (row.first < 0 || row.first > row.last || row.representative < row.first ||
        row.representative > row.last) {
      throw RunFileError(where(t, r) + ": need 0 <= first <= representative <= last, got " +
                         std::to_string(row.first) + " <= " + std::to_string(row.representative) +
                         " <= " + std::to_string(row.last));
    }
    rows.push_back(row);
  }
  return rows;
}

TopologyFile loadTopology(const std::string& path) {
  const JsonValue root = readJsonFile(path);
  TopologyFile topo;
  try {
    topo.probability = root.at("probability").asNumber("probability");
    if (const JsonValue* p = root.find("particles"))
      topo.particles = static_cast<int>(p->asNumber("particles"));
    // The filter's estimate at the end (`map`); each key is optional, as in a hand-made file.
    if (const JsonValue* c = root.find("current_node")) {
      TopologyFile::Estimate e;
      e.current_node = static_cast<int>(c->asNumber("current_node"));
      if (const JsonValue* v = root.find("current_node_probability"))
        e.current_node_probability = v->asNumber("current_node_probability");
      if (const JsonValue* v = root.find("effective_sample_size"))
        e.effective_sample_size = v->asNumber("effective_sample_size");
      if (const JsonValue* v = root.find("distinct_topologies"))
        e.distinct_topologies = static_cast<int>(v->asNumber("distinct_topologies"));
      if (const JsonValue* v = root.find("earlier_places"))
        e.earlier_places = static_cast<int>(v->asNumber("earlier_places"));
      if (const JsonValue* alternatives = root.find("alternatives")) {
        for (const JsonValue& a : alternatives->asArray("alternatives")) {
          TopologyFile::Alternative alternative;
          alternative.probability = a.at("probability").asNumber("alternatives[].probability");
          alternative.nodes = static_cast<int>(a.at("nodes").asNumber("alternatives[].nodes"));
          alternative.first_difference =
              static_cast<int>(a.at("first_difference").asNumber("alternatives[].first_difference"));
          e.alternatives.push_back(alternative);
        }
      }
      topo.estimate = std::move(e);
    }
    for (const JsonValue& n : root.at("nodes").asArray("nodes")) {
      TopologyFile::Node node;
      node.id = static_cast<int>(n.at("id").asNumber("nodes[].id"));
      for (const JsonValue& p : n.at("places").asArray("nodes[].places")) {
        node.places.push_back(static_cast<int>(p.asNumber("nodes[].places[]")));
      }
      if (const JsonValue* reps = n.find("representative_frames")) {
        for (const JsonValue& f : reps->asArray("nodes[].representative_frames")) {
          node.representative_frames.push_back(
              static_cast<std::int64_t>(f.asNumber("nodes[].representative_frames[]")));
        }
      }
      if (const JsonValue* earlier = n.find("earlier_places")) {
        for (const JsonValue& p : earlier->asArray("nodes[].earlier_places"))
          node.earlier_places.push_back(static_cast<int>(p.asNumber("nodes[].earlier_places[]")));
      }
      topo.nodes.push_back(std::move(node));
    }
    if (const JsonValue* edges = root.find("edges")) {
      for (const JsonValue& e : edges->asArray("edges")) {
        TopologyFile::Edge edge;
        edge.from = static_cast<int>(e.at("from").asNumber("edges[].from"));
        edge.to = static_cast<int>(e.at("to").asNumber("edges[].to"));
        if (const JsonValue* c = e.find("count")) edge.count = static_cast<int>(c->asNumber("edges[].count"));
        topo.edges.push_back(edge);
      }
    }
    if (const JsonValue* history = root.find("history")) {
      for (const JsonValue& h : history->asArray("history")) {
        TopologyFile::Step step;
        step.place = static_cast<int>(h.at("place").asNumber("history[].place"));
        if (const JsonValue* v = h.find("node")) step.node = static_cast<int>(v->asNumber("history[].node"));
        if (const JsonValue* v = h.find("probability"))
          step.probability = v->asNumber("history[].probability");
        if (const JsonValue* v = h.find("best_topology_probability")) {
          step.best_topology_probability = v->asNumber("history[].best_topology_probability");
        }
        if (const JsonValue* v = h.find("effective_sample_size")) {
          step.effective_sample_size = v->asNumber("history[].effective_sample_size");
        }
        if (const JsonValue* v = h.find("is_new")) step.is_new = v->asBool("history[].is_new");
        topo.history.push_back(step);
      }
    }
  } catch (const JsonError& e) {
    throw RunFileError(path + ": " + e.what());
  }
  return topo;
}

std::vector<TimingRow> loadTiming(const std::string& path) {
  const CsvTable t = readCsv(path);
  const int frame = t.column("frame"), fp = t.column("fingerprint_ms", false),
            seg = t.column("segment_ms", false), filt = t.column("filter_ms", false);
  std::vector<TimingRow> rows;
  auto get = [&](std::size_t r, int c) {
    if (c < 0) return 0.0;
    const double v = t.number(r, c, true);
    return std::isfinite(v) ? v : 0.0;
  };
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    TimingRow row{t.integer(r, frame), get(r, fp), get(r, seg), std::nullopt};
    // `segment` has no filter: an empty column.
    if (filt >= 0 && !t.rows[r][static_cast<std::size_t>(filt)].empty()) row.filter_ms = get(r, filt);
    rows.push_back(row);
  }
  return rows;
}

std::vector<std::string> loadSources(const fs::path& dir) {
  std::vector<std::string> sources;
  if (std::ifstream in(dir / run_files::kSources); in) {
    for (std::string line; std::getline(in, line);)
      if (!line.empty()) sources.push_back(line);
  }
  return sources;
}

RunSettings loadSettings(const fs::path& dir) {
  RunSettings settings;
  if (std::ifstream in(dir / run_files::kSettings); in) {
    int number = 0;
    for (std::string line; std::getline(in, line);) {
      ++number;
      if (line.empty() || line[0] == '#') continue;
      const auto eq = line.find(" = ");
      if (eq == std::string::npos)
        throw RunFileError((dir / run_files::kSettings).string() + ":" + std::to_string(number) +
                           ": expected 'key = value', got '" + line + "'");
      settings.emplace_back(line.substr(0, eq), line.substr(eq + 3));
    }
  }
  return settings;
}

RunData loadRun(const std::string& dir) {
  if (!fs::is_directory(dir)) throw RunFileError(dir + ": not a run folder (no such directory)");
  RunData run;
  run.dir = dir;
  const fs::path root(dir);
  if (!fs::exists(root / run_files::kFrames)) {
    throw RunFileError((root / run_files::kFrames).string() +
                       ": missing; give a folder written by `toposlam segment` or `toposlam map`");
  }
  run.frames = loadFrames((root / run_files::kFrames).string());
  {
    // The header alone (loadFrames read and checked the whole file).
    std::ifstream in((root / run_files::kFrames).string());
    CsvReader reader(in);
    CsvRecord header;
    run.has_frame_matches = reader.next(header) && std::find(header.fields.begin(), header.fields.end(),
                                                             "match") != header.fields.end();
  }
  const auto frame_count = static_cast<std::int64_t>(run.frames.size());
  // Places must lie inside frames.csv (loadPlaces already checked 0 <= first <= representative <= last).
  auto loadPlacesWithin = [&](const std::string& name) {
    const std::string path = (root / name).string();
    std::vector<PlaceRecord> places = loadPlaces(path);
    for (const PlaceRecord& p : places) {
      if (p.last >= frame_count) {
        throw RunFileError(path + ":" + std::to_string(p.line) + ": place " + std::to_string(p.place) +
                           " spans frames " + std::to_string(p.first) + ".." + std::to_string(p.last) +
                           " but frames.csv has " + std::to_string(frame_count) +
                           " frames (a damaged or mixed-up run folder)");
      }
    }
    return places;
  };
  if (fs::exists(root / run_files::kPlaces)) run.places = loadPlacesWithin(run_files::kPlaces);
  if (fs::exists(root / run_files::kDroppedPlaces)) run.dropped_places = loadPlacesWithin(run_files::kDroppedPlaces);
  if (fs::exists(root / run_files::kTopology)) run.topology = loadTopology((root / run_files::kTopology).string());
  if (fs::exists(root / run_files::kTiming)) run.timing = loadTiming((root / run_files::kTiming).string());
  run.sources = loadSources(root);
  run.settings = loadSettings(root);
  run.traversal_starts.push_back(0);
  for (std::size_t f = 1; f < run.frames.size(); ++f) {
    if (run.frames[f].time_s < run.frames[f - 1].time_s)
      run.traversal_starts.push_back(static_cast<std::int64_t>(f));
  }
  return run;
}
}  // namespace toposlam
