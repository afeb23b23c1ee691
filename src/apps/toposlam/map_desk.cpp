// The map on the desk (see map_desk.hpp): open a map file, say what it holds, turn it into a run folder.
#include "map_desk.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <map>
#include <stdexcept>

#include "toposlam/config/config_keys.hpp"
#include "toposlam/config/daemon_config.hpp"
#include "toposlam/config/method_preset.hpp"
#include "toposlam/pipeline/map_files.hpp"

namespace toposlam::cli {

namespace {

namespace fs = std::filesystem;

std::string utcText(fs::file_time_type time) {
  const auto system = std::chrono::file_clock::to_sys(time);
  const std::time_t seconds = std::chrono::system_clock::to_time_t(
      std::chrono::time_point_cast<std::chrono::system_clock::duration>(system));
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

/// Node of each observation in the best topology (-1: none).
std::vector<int> nodeOfObservation(const DeskMap& map) {
  std::vector<int> nodes(map.origins.origins.size(), -1);
  for (const TopologyNode& node : map.best.nodes)
    for (const int observation : node.places)
      if (observation >= 0 && static_cast<std::size_t>(observation) < nodes.size())
        nodes[static_cast<std::size_t>(observation)] = node.id;
  return nodes;
}

/// Where each observation lies in the exported frames.csv: runs one after the other; an observation of
/// unknown origin gets a frame of its own after them.
struct Layout {
  std::vector<std::int64_t> run_offset;  ///< first exported frame of each run
  std::vector<std::int64_t> first, last, representative;  ///< per observation, exported numbering
  std::int64_t frames = 0;
};

bool knownOrigin(const ObservationOrigin& o) { return o.run >= 0 && o.representative_frame >= 0; }

std::vector<std::int64_t> runFrameCounts(const MapApplicationData& data) {
  std::vector<std::int64_t> counts = data.run_frames;
  for (const ObservationOrigin& o : data.origins) {
    if (!knownOrigin(o)) continue;
    const auto run = static_cast<std::size_t>(o.run);
    if (counts.size() <= run) counts.resize(run + 1, 0);
    counts[run] = std::max({counts[run], o.representative_frame + 1, o.last_frame + 1});
  }
  return counts;
}

Layout layoutOf(const MapApplicationData& data) {
  Layout layout;
  for (const std::int64_t count : runFrameCounts(data)) {
    layout.run_offset.push_back(layout.frames);
    layout.frames += count;
  }
  for (const ObservationOrigin& o : data.origins) {
    if (!knownOrigin(o)) {
      layout.first.push_back(layout.frames);
      layout.last.push_back(layout.frames);
      layout.representative.push_back(layout.frames++);
      continue;
    }
    const std::int64_t offset = layout.run_offset[static_cast<std::size_t>(o.run)];
    const bool span = o.first_frame >= 0 && o.last_frame >= o.first_frame;
    layout.first.push_back(offset + (span ? o.first_frame : o.representative_frame));
    layout.last.push_back(offset + (span ? o.last_frame : o.representative_frame));
    layout.representative.push_back(offset + o.representative_frame);
  }
  return layout;
}

/// Frame times: a place's frames between its first and last times, a traversal's first frame at its start
/// time, any other frame at the time before it (0 when none), so that a new traversal shows as time going
/// back as in the original frames.csv.
std::vector<double> frameTimes(const MapApplicationData& data, const Layout& layout) {
  std::vector<double> times(static_cast<std::size_t>(layout.frames), std::nan(""));
  for (const MapTraversal& t : data.traversals) {
    if (t.run < 0 || static_cast<std::size_t>(t.run) >= layout.run_offset.size()) continue;
    const std::int64_t f = layout.run_offset[static_cast<std::size_t>(t.run)] + t.start_frame;
    if (f >= 0 && f < layout.frames) times[static_cast<std::size_t>(f)] = t.start_time_s;
  }
  for (std::size_t k = 0; k < data.origins.size(); ++k) {
    const ObservationOrigin& o = data.origins[k];
    if (std::isnan(o.first_time_s) || std::isnan(o.last_time_s)) continue;
    const std::int64_t n = layout.last[k] - layout.first[k];
    for (std::int64_t i = 0; i <= n; ++i) {
      const double share = n == 0 ? 0.0 : static_cast<double>(i) / static_cast<double>(n);
      times[static_cast<std::size_t>(layout.first[k] + i)] = o.first_time_s + share * (o.last_time_s - o.first_time_s);
    }
  }
  double previous = 0.0;
  for (double& t : times) {
    if (!std::isnan(t)) previous = t;
    t = previous;
  }
  return times;
}

std::vector<FrameRecord> exportedFrames(const DeskMap& map, const Layout& layout, const std::vector<int>& nodes) {
  const std::vector<double> times = frameTimes(map.origins, layout);
  std::vector<FrameRecord> frames(static_cast<std::size_t>(layout.frames));
  for (std::size_t f = 0; f < frames.size(); ++f) {
    frames[f].frame = static_cast<std::int64_t>(f);
    frames[f].time_s = times[f];
  }
  for (std::size_t k = 0; k < layout.first.size(); ++k) {
    for (std::int64_t f = layout.first[k]; f <= layout.last[k]; ++f) {
      frames[static_cast<std::size_t>(f)].place = static_cast<int>(k);
      frames[static_cast<std::size_t>(f)].node = nodes[k];
      frames[static_cast<std::size_t>(f)].node_probability = map.origins.origins[k].node_probability;
    }
  }
  return frames;
}

std::vector<PlaceRecord> exportedPlaces(const DeskMap& map, const Layout& layout, const std::vector<int>& nodes) {
  std::vector<PlaceRecord> places;
  const TopologyParticleFilter& filter = map.topology->filter();
  for (std::size_t k = 0; k < layout.first.size(); ++k) {
    const ObservationOrigin& o = map.origins.origins[k];
    PlaceRecord p;
    p.place = static_cast<int>(k);
    p.first = layout.first[k];
    p.last = layout.last[k];
    p.representative = layout.representative[k];
    p.keypoints = o.keypoints;
    if (p.keypoints == 0)
      if (const auto stored = filter.storedRepresentative(static_cast<int>(k))) p.keypoints = stored->keypointCount();
    p.node = nodes[k];
    p.end = o.end;
    places.push_back(p);
  }
  return places;
}

TopologyFile exportedTopology(const DeskMap& map, const Layout& layout) {
  TopologyFile file;
  file.probability = map.estimate.best.probability;
  file.particles = map.topology->filter().config().particles;
  file.estimate = topologyFileEstimate(map.estimate, 0);
  for (const TopologyNode& node : map.best.nodes) {
    if (node.places.empty()) continue;
    TopologyFile::Node& n = file.nodes.emplace_back();
    n.id = node.id;
    n.places = node.places;
    for (const int observation : node.places)
      n.representative_frames.push_back(layout.representative[static_cast<std::size_t>(observation)]);
  }
  for (const TopologyEdge& edge : map.best.edges) file.edges.push_back({edge.from, edge.to, edge.count});
  for (std::size_t k = 0; k < map.origins.origins.size(); ++k) {
    const ObservationOrigin& o = map.origins.origins[k];
    if (std::isnan(o.node_probability)) continue;  // not recorded (toposlamd, an older `map`)
    TopologyFile::Step& step = file.history.emplace_back();
    step.place = static_cast<int>(k);
    step.node = o.step_node;
    step.probability = o.node_probability;
    if (!std::isnan(o.best_topology_probability)) step.best_topology_probability = o.best_topology_probability;
    if (!std::isnan(o.effective_sample_size)) step.effective_sample_size = o.effective_sample_size;
  }
  return file;
}

/// A daemon's map records no runs or sources of its own: its settings name the source and the last frame the
/// map holds, which give run 0's frames and its one traversal.
void completeDaemonOrigins(DeskMap& map) {
  MapApplicationData& data = map.origins;
  if (data.writer != MapApplicationData::Writer::Daemon || !data.run_frames.empty()) return;
  if (const auto last = map.settings.find(kMapSourceLastFrameKey); last != map.settings.end()) {
    try {
      data.run_frames = {std::stoll(last->second) + 1};
    } catch (const std::exception&) {
      // not a number: the frames are counted from the places alone
    }
  }
  if (const auto source = map.settings.find(kMapSourceKey); source != map.settings.end() && !source->second.empty())
    data.traversals.push_back(MapTraversal{0, 0, std::nan(""), source->second});
}

}  // namespace

bool looksLikeMapFile(const fs::path& path) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) return false;
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  return in.read(magic, sizeof magic) && std::string(magic, sizeof magic) == "TSLMAP\r\n";
}

DeskMap openDeskMap(const fs::path& path, const std::string& command) {
  DeskMap map;
  map.path = path;
  std::error_code error;
  if (fs::is_directory(path, error))
    throw std::runtime_error(command + ": " + path.string() + " is a folder, not a map file (give its map.tsm)");
  map.similarity = std::make_unique<NgramSimilarity>(methodPreset("default").similarity);
  map.clock = std::make_unique<ManualClock>();
  LoadedMap loaded;
  try {
    loaded = MapStore::load(path, *map.similarity);
  } catch (const MapStoreError& e) {
    throw std::runtime_error(command + ": " + e.what());
  }
  map.bytes = fs::file_size(path, error);
  map.saved_utc = utcText(fs::last_write_time(path, error));
  map.settings = loaded.settings;
  map.origins = decodeMapApplicationData(loaded.application_data, loaded.filter->observationCount());
  completeDaemonOrigins(map);
  map.topology = std::make_unique<ParticleFilterTopologyStage>(loaded.filter->config(), *map.similarity, *map.clock,
                                                               TopologyStageConfig{});
  map.topology->adoptMap(std::move(loaded));
  map.best = map.topology->topology();
  map.estimate = map.topology->filter().estimate(3);
  return map;
}

int nodeCount(const DeskMap& map) {
  return static_cast<int>(std::count_if(map.best.nodes.begin(), map.best.nodes.end(),
                                        [](const TopologyNode& n) { return !n.places.empty(); }));
}

std::string presetOf(const MapSettings& settings) {
  std::string closest;
  int fewest = -1;
  for (const std::string& name : methodPresetNames()) {
    DaemonConfig config;
    applyMethodPreset(name, config);
    int differ = 0, compared = 0;
    for (const auto& [key, value] : mapDecisionSettings(config)) {
      compared += settings.count(key) > 0 ? 1 : 0;
      differ += settingDiffers(settings, {{key, value}}, key) ? 1 : 0;
    }
    if (compared == 0) return "unknown";
    if (differ == 0) return name;
    if (fewest < 0 || differ < fewest) {
      fewest = differ;
      closest = name;
    }
  }
  return "custom (" + std::to_string(fewest) + " settings differ from " + closest + ")";
}

TopologyFile::Estimate topologyFileEstimate(const TopologyEstimate& estimate, int earlier_places) {
  TopologyFile::Estimate e;
  e.current_node = estimate.current_node;
  e.current_node_probability = estimate.current_node_probability;
  e.effective_sample_size = estimate.effective_sample_size;
  e.distinct_topologies = estimate.distinct_topologies;
  e.earlier_places = earlier_places;
  for (const TopologyHypothesis& h : estimate.alternatives)
    e.alternatives.push_back(TopologyFile::Alternative{h.probability, h.node_count, h.first_difference});
  return e;
}

ExportedRun exportedRun(const DeskMap& map) {
  const Layout layout = layoutOf(map.origins);
  const std::vector<int> nodes = nodeOfObservation(map);
  ExportedRun run;
  run.frames = exportedFrames(map, layout, nodes);
  run.places = exportedPlaces(map, layout, nodes);
  run.topology = exportedTopology(map, layout);
  for (const MapTraversal& t : map.origins.traversals) run.sources.push_back(t.source);
  run.settings = {{"exported_from", fs::absolute(map.path).lexically_normal().string()},
                  {"written_by", writerName(map.origins.writer)},
                  {"saved", map.saved_utc},
                  {"preset", presetOf(map.settings)}};
  for (const auto& [key, value] : map.settings) run.settings.emplace_back("map." + key, value);
  return run;
}

void writeExportedRun(const DeskMap& map, const fs::path& dir) {
  const ExportedRun run = exportedRun(map);
  createRunFolder(dir);
  writeFrames(dir, run.frames, FrameColumns::WithNodeProbability);
  writePlaces(dir, run.places);
  writeTopology(dir, run.topology);
  if (!run.sources.empty()) writeSources(dir, run.sources);
  writeSettings(dir, run.settings);
}

}  // namespace toposlam::cli
