// `toposlam map SOURCE... --out DIR`: offline topological SLAM. Each source's frames go through VPACK
// (chapter 3) and the Fiedler segmenter (chapter 4); every kept place's representative is one step of the
// topology particle filter (chapter 5). Several sources are processed one after another as consecutive
// traversals (the thesis stacks two runs); each source gets a fresh segmentation window, the filter
// carries on. --resume MAP continues a saved map (its filter config and random state come from the file).
//
// Writes the run folder of docs/run-folder.md: frames.csv, places.csv, dropped_places.csv,
// topology.json, topology.dot (+ .svg/.png when Graphviz' `dot` is installed), timing.csv, lambda2.svg
// and map.tsm. Frames and places are numbered from 0 over all sources of this run, in stream order; with
// --resume, the resumed map's places appear in topology.json as `earlier_places` (filter observation
// numbers). The map's application data keeps, per observation, the run and frame it came from.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "config_options.hpp"
#include "offline_run_io.hpp"
#include "toposlam/config/config_keys.hpp"
#include "toposlam/config/daemon_config.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/io/source_uri.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/pipeline/clock.hpp"
#include "toposlam/pipeline/frame_source.hpp"
#include "toposlam/platform/programs.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"
#include "toposlam/pipeline/offline_runner.hpp"
#include "toposlam/pipeline/stage_assembly.hpp"
#include "toposlam/pipeline/frame_failures.hpp"
#include "toposlam/run_folder/run_folder.hpp"
#include "toposlam/topology/frame_loop_closures.hpp"
#include "toposlam/pipeline/map_files.hpp"
#include "toposlam/topology/map_store.hpp"
#include "toposlam/topology/sequence_loop_closures.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"
#include "map_application_data.hpp"
#include "motion_input.hpp"
#include "progress.hpp"

namespace toposlam::cli {

namespace {

namespace fs = std::filesystem;

struct MapOptions {
  std::vector<std::string> sources;
  std::string out;
  std::string resume;
  bool resume_other_source = false;  ///< --resume-other-source: continue a map made from another source
  bool resume_other_settings = false;  ///< --resume-other-settings: continue a map made with other settings
  ConfigOptions config;  ///< -c, --set, --preset and the aliases of the keys (config_options.hpp)
  MotionOptions motion;
  bool json = false;   ///< --json: the summary as one JSON object on stdout
  bool quiet = false;  ///< --quiet: no progress and no per-place lines on stderr
  int loop_min_gap = 10;  ///< frame-level loop closures by visits: detections at least this many frames back
};

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// The last path component of a source URI's path ("images:/d/corridor/ref?fps=1" -> "ref").
std::string sourceLabel(const std::string& uri) {
  std::string path = uri.substr(uri.find(':') == std::string::npos ? 0 : uri.find(':') + 1);
  if (const auto q = path.find('?'); q != std::string::npos) path = path.substr(0, q);
  while (path.size() > 1 && path.back() == '/') path.pop_back();
  const std::string label = fs::path(path).filename().string();
  return label.empty() ? "source" : label;
}

std::string shellQuote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

/// The run folder's map.tsm is ours until the end: a second `map` (or a toposlamd) on it is refused before
/// any work, and temporaries a killed run left there are removed.
MapLock lockRunFolderMap(const fs::path& map_path, const std::string& out) {
  MapLock lock = MapLock::acquire(map_path);
  if (const int orphans = MapStore::removeOrphanedTemporaries(map_path); orphans > 0)
    std::cerr << "map: removed " << orphans << " temporary files of an interrupted save in " << out << "\n";
  return lock;
}

/// What a map made by this run records: the keys toposlamd records (the key table's recorded_in_map, read
/// from the settings this run uses, with the filter's `filter`), the keypoint backend and the first source;
/// so that toposlamd (and --resume) can tell a map made with other settings (`--preset thesis` against the
/// default).
MapSettings mapSettingsOf(const DaemonConfig& run_config, const TopologyFilterConfig& filter,
                          const std::string& source_uri) {
  DaemonConfig config = run_config;
  config.topology = filter;
  MapSettings settings = fingerprintMapSettings(config.fingerprint);
  for (auto& [key, value] : mapDecisionSettings(config)) settings[key] = std::move(value);
  settings[kMapSourceKey] = sourceIdentity(source_uri);
  return settings;
}

/// Where the run's observations come from: per observation so far (a resumed map's), then this run's.
struct StartingFilter {
  MapApplicationData origins;  ///< per observation so far (the resumed map's), then this run's
  int run_number = 0;          ///< this run's, in the origins
};

/// --resume: the saved map replaces the topology stage's new filter (its settings with it; the stage's
/// candidate selection stays this run's); refused (ConfigError naming the option that would accept it)
/// when it was made with other keypoints, from another source, or with other settings (`settings_for(uri)`:
/// what this run records for a source).
StartingFilter resumedFilter(const MapOptions& o, ParticleFilterTopologyStage& topology,
                             const NgramSimilarity& similarity,
                             const std::function<MapSettings(const std::string&)>& settings_for, bool localizing) {
  const bool other_source_allowed = o.resume_other_source || localizing;  // localising is a later run
  for (const char* key : {"topology.particles", "topology.alpha", "topology.seed", "topology.max_representatives_per_node"})
    if (keyGiven(o.config, key))
      throw std::invalid_argument(
          "map: --particles, --alpha, --seed and --max-representatives (topology.particles, topology.alpha, "
          "topology.seed, topology.max_representatives_per_node) come from the map when resuming; drop them or "
          "start a new map");
  LoadedMap loaded = MapStore::load(o.resume, similarity);
  // ORB descriptors mean nothing to a SIFT run (and so on), and another source (a simulated office, a
  // camera elsewhere) or other settings are no continuation unless the user says so: the map says what
  // it was made with.
  const std::map<std::string, std::string> decision_keys = mapDecisionSettings(DaemonConfig());
  bool unrecorded = false;
  for (const std::string& uri : o.sources) {
    MapSettings current = settings_for(uri);
    std::string hint;
    if (settingDiffers(loaded.settings, current, "keypoints")) hint += "--keypoints";
    if (other_source_allowed)
      current.erase(kMapSourceKey);
    else if (settingDiffers(loaded.settings, current, kMapSourceKey))
      hint += std::string(hint.empty() ? "" : "; ") + "--resume-other-source continues it from this source";
    bool other_settings = false;
    for (const auto& [key, value] : decision_keys) {
      other_settings = other_settings || settingDiffers(loaded.settings, current, key);
      unrecorded = unrecorded || loaded.settings.count(key) == 0;
      if (o.resume_other_settings) current.erase(key);
    }
    if (other_settings && !o.resume_other_settings)
      hint += std::string(hint.empty() ? "" : "; ") + "--resume-other-settings continues it with this run's settings";
    const std::string refusal = MapStore::checkSettings(loaded.settings, current, o.resume);
    if (!refusal.empty()) throw ConfigError("map: " + refusal + " (" + hint + ")");
  }
  if (unrecorded)
    std::cerr << "map: warning: " << o.resume << " records the keypoints and the source only (it was made by an older "
              << "toposlam): its other settings cannot be compared; continuing it with this run's\n";
  StartingFilter start;
  start.origins = decodeMapApplicationData(loaded.application_data, loaded.filter->observationCount());
  topology.adoptMap(std::move(loaded));
  for (const auto& origin : start.origins.origins) start.run_number = std::max(start.run_number, origin.run + 1);
  start.run_number = std::max(start.run_number, static_cast<int>(start.origins.run_frames.size()));
  std::cerr << "map: resumed " << o.resume << " (" << topology.observations() << " places)\n";
  return start;
}

/// What the sources' traversals leave besides the runner's rows.
struct Traversals {
  std::vector<TimingRow> timing;  ///< per segmented frame
  FrameFailures refused;          ///< frames the stages refused (frame_failures.hpp)
  /// Every segmented frame's fingerprint (run numbering), for the frame-level loop closures by visits at the
  /// end; empty by sequence (each frame's answer came online).
  std::vector<std::shared_ptr<const Fingerprint>> frame_fingerprints;
};

/// Where a kept place of this run came from and the filter's estimate after its step (`e`), for the map's
/// application data.
ObservationOrigin originOf(const SegmentedPlace& place, int run_number, const TopologyEstimate& e) {
  ObservationOrigin o;
  o.step_node = e.current_node;
  o.node_probability = e.current_node_probability;
  o.best_topology_probability = e.best.probability;
  o.effective_sample_size = e.effective_sample_size;
  o.run = run_number;
  o.representative_frame = place.representative_frame;
  o.first_frame = place.first_frame;
  o.last_frame = place.last_frame;
  o.first_time_s = place.first_time_s;
  o.last_time_s = place.last_time_s;
  o.keypoints = place.representative_keypoints;
  o.end = placeEndName(place.end);
  return o;
}

/// This run's frame count and the start time of each of its traversals, once the sources are done.
void finishRunOrigins(MapApplicationData& origins, int run_number, const SegmentationRun& all) {
  origins.run_frames.resize(std::max(origins.run_frames.size(), static_cast<std::size_t>(run_number) + 1), 0);
  origins.run_frames[static_cast<std::size_t>(run_number)] = static_cast<std::int64_t>(all.frames.size());
  for (MapTraversal& t : origins.traversals) {
    if (t.run == run_number && t.start_frame >= 0 && static_cast<std::size_t>(t.start_frame) < all.frames.size())
      t.start_time_s = all.frames[static_cast<std::size_t>(t.start_frame)].time_s;
  }
}

/// Every source, one traversal after the other, through the runner: fingerprint, segment, and a filter step
/// for every kept place; `origins` gets one entry per step; with `keep_fingerprints`, every frame's
/// fingerprint (the frame-level closures by visits need them at the end).
Traversals traverseSources(const MapOptions& o, OfflineRunner& runner,
                           FiedlerSegmentationStage& segmentation_stage, std::optional<MotionReplay>& motion,
                           MapApplicationData& origins, int run_number, bool keep_fingerprints) {
  Traversals done;
  Progress* progress = nullptr;  // the current source's progress line (cleared before a log line)
  auto mapPlace = [&](const SegmentedPlace& place) {
    if (place.dropped) return;
    if (progress != nullptr) progress->clearLine();
    const auto start = std::chrono::steady_clock::now();
    const MappedPlace mapped = *runner.mapPlace(place);
    if (!done.timing.empty()) done.timing.back().filter_ms = *done.timing.back().filter_ms + msSince(start);
    const TopologyEstimate& e = mapped.estimate;
    origins.origins.push_back(originOf(place, run_number, e));
    if (o.quiet) return;
    std::fprintf(stderr,
                 "map: place %lld (frames %lld-%lld) -> node %d p=%.2f, best topology p=%.2f, ESS %.0f\n",
                 static_cast<long long>(place.index), static_cast<long long>(place.first_frame),
                 static_cast<long long>(place.last_frame), e.current_node, e.current_node_probability,
                 e.best.probability, e.effective_sample_size);
  };

  for (const std::string& uri : o.sources) {
    std::unique_ptr<FrameSource> source = openSource(uri);
    if (!o.quiet) std::cerr << "map: " << source->describe() << "\n";
    runner.beginTraversal();  // fresh segmentation window per traversal
    origins.traversals.push_back(MapTraversal{run_number, static_cast<std::int64_t>(runner.run().frames.size()),
                                              std::numeric_limits<double>::quiet_NaN(), absoluteSourceUri(uri)});
    // Each traversal has its own clock, with any step back inside it cut out (the segmentation stage's;
    // docs/reliability.md, "Clock jumps"); the next source starts its own, so where it goes back a new
    // traversal begins (frames.csv).
    Progress source_progress("map", "frames", source->frameCountHint(), o.quiet);
    progress = &source_progress;
    std::int64_t read = 0;
    while (std::optional<Frame> frame = source->next()) {
      source_progress.update(++read);
      TimingRow t;
      t.frame = static_cast<std::int64_t>(done.timing.size());
      t.filter_ms = 0.0;
      auto start = std::chrono::steady_clock::now();
      std::shared_ptr<const Fingerprint> fingerprint;
      try {
        fingerprint = runner.fingerprint(frame->image, frame->grey);
      } catch (const std::exception& e) {
        // A frame the stages refuse (empty, too small): skipped and counted, as toposlamd does.
        if (done.refused.count())
          std::cerr << "map: skipping frame '" << frame->name << "' (" << done.refused.total() << " so far): "
                    << e.what() << "\n";
        continue;
      }
      t.fingerprint_ms = msSince(start);
      start = std::chrono::steady_clock::now();
      if (keep_fingerprints) done.frame_fingerprints.push_back(fingerprint);
      // With several sources, names carry their source's folder ("ref/0001.jpg", "query/0001.jpg") so
      // they stay unique in frames.csv and pair ground truths can name either traversal.
      const std::string name = o.sources.size() > 1 ? sourceLabel(uri) + "/" + frame->name : frame->name;
      if (motion) motion->feedUpTo(frame->timestamp_s, segmentation_stage);
      const SegmenterStep step = runner.segment(frame->timestamp_s, name, std::move(fingerprint));
      t.segment_ms = msSince(start);
      done.timing.push_back(t);
      frame.reset();  // hand the buffer back to the source
      if (step.closed_place) mapPlace(*step.closed_place);
    }
    if (auto last = runner.finishTraversal()) mapPlace(*last);
    source_progress.finish();
    progress = nullptr;
    // By reason, as toposlamd's last log line: "map: skipped 3 frames (truncated 2, corrupt 1)".
    if (const SkippedFrames skipped = source->skippedByReason(); skipped.total() > 0)
      std::cerr << "map: " << skippedFramesText(skipped) << "\n";
    if (const FrameTimeline& timeline = segmentation_stage.sourceTimeline(); timeline.stepsBack() > 0)
      std::cerr << timelineSummary(timeline, "map") << "\n";
  }
  return done;
}

/// settings.txt: what the run was made with, for the report's header (and a reader of the run folder).
void writeRunSettings(const fs::path& out_dir, const MapOptions& o, const std::string& preset,
                      const VpackConfig& vpack, const FiedlerSegmenterConfig& segmenter_config,
                      const TopologyFilterConfig& topo, const SequenceEvidenceConfig& evidence) {
  const auto real = [](double v) {
    std::ostringstream text;
    text << v;
    return text.str();
  };
  const FiedlerSegmenterConfig& s = segmenter_config;
  const std::string window =
      s.window_s > 0
          ? real(s.window_s) + " s (" + std::to_string(s.min_window_frames) + "-" + std::to_string(s.window) +
                " frames)"
          : std::to_string(s.window) + " frames";
  const std::string representative =
      s.representative == RepresentativeChoice::PlaceMedoid
          ? std::string("place-medoid, sampled every ") + real(s.representative_interval_s) + " s"
          : std::string("window-degree");
  const std::string sequence_evidence =
      evidence.weight > 0.0
          ? "weight " + real(evidence.weight) + ", detections scored at least " + real(evidence.min_score)
          : "off";
  const std::string frame_loops =
      evidence.frame_revisits
          ? "sequence, online, memories " + real(evidence.memory_s) + " s (" + std::to_string(evidence.loop.scales) +
                " scales), at least " + real(evidence.min_gap_s) + " s back, score at least " + real(evidence.min_score)
          : "visits, at least " + std::to_string(o.loop_min_gap) + " frames back";
  writeSettings(out_dir, {{"toposlam", TOPOSLAM_VERSION},
                          {"preset", preset},
                          {"keypoints", std::string(toString(vpack.keypoints.backend)) + ", at most " +
                                            std::to_string(vpack.keypoints.max_keypoints) + " per frame"},
                          {"segmentation.window", window},
                          {"segmentation.gamma", real(s.valley.gamma)},
                          {"segmentation.delta", real(s.valley.delta)},
                          {"segmentation.cut", toString(s.cut_placement)},
                          {"segmentation.representative", representative},
                          {"segmentation.place_samples",
                           s.place_samples > 0 ? std::to_string(s.place_samples) + ", at most one per " +
                                                     real(s.representative_interval_s) + " s"
                                               : std::string("0 (the representative alone)")},
                          {"topology.particles", std::to_string(topo.particles)},
                          {"topology.likelihood", toString(topo.likelihood)},
                          {"topology.seed", std::to_string(topo.seed)},
                          {"topology.sequence_evidence", sequence_evidence},
                          {"frame_loops", frame_loops}});
}

/// frames.csv's rows with their frame-level loop closures (docs/topology.md): by sequence, the answer each
/// frame got online as it arrived (what toposlamd publishes in place_t); by visits (the thesis preset),
/// each frame on a node seen on an earlier visit gets that visit's most similar frame, scored by
/// similarity x the place's node probability at its step (the frames' fingerprints, resized to the run's
/// frames).
std::vector<FrameRecord> frameRowsWithLoopClosures(
    const OfflineRunner& runner, const std::vector<std::int64_t>& place_nodes,
    std::vector<std::shared_ptr<const Fingerprint>>& frame_fingerprints, const NgramSimilarity& similarity,
    bool by_sequence, int loop_min_gap) {
  const SegmentationRun& all = runner.run();
  std::vector<FrameRecord> frame_rows = frameRows(all, place_nodes);
  std::vector<double> place_probability(all.places.size(), 0.0);
  for (const MappedPlace& step : runner.steps()) {
    const auto p = static_cast<std::size_t>(step.place.index);
    if (p < place_probability.size()) place_probability[p] = step.estimate.current_node_probability;
  }
  std::vector<FrameMatch> visits;
  if (!by_sequence) {
    std::vector<std::int64_t> place_of_frame;
    for (const auto& row : all.frames) place_of_frame.push_back(row.place);
    frame_fingerprints.resize(all.frames.size());
    visits = matchFramesToEarlierVisits(place_of_frame, place_nodes, place_probability, frame_fingerprints,
                                        similarity, loop_min_gap);
  }
  const std::vector<RevisitEstimate>& online = runner.revisits();
  for (std::size_t f = 0; f < frame_rows.size(); ++f) {
    FrameRecord& row = frame_rows[f];
    if (row.place >= 0 && static_cast<std::size_t>(row.place) < place_probability.size())
      row.node_probability = place_probability[static_cast<std::size_t>(row.place)];
    if (by_sequence && f < online.size()) {
      row.match = online[f].match_frame;
      row.match_score = online[f].score;
    } else if (!by_sequence && f < visits.size()) {
      row.match = visits[f].match_frame;
      row.match_score = visits[f].score;
    }
  }
  return frame_rows;
}

/// A node of the best topology as the run folder shows it: this run's places (run numbering) with their
/// representative frames, and the resumed map's observations (`earlier_places`).
struct NodeInfo {
  std::vector<std::int64_t> places, representative_frames, earlier_places;
};

/// The best topology's nodes and edges (over all observations, resumed ones included): the topology stage's
/// snapshot, the one toposlamd publishes. Observations before `first_observation` are the resumed map's.
struct RunTopology {
  std::map<int, NodeInfo> nodes;             ///< by node id; nodes without places left out
  std::map<std::pair<int, int>, int> edges;  ///< (from, to) -> traversals
};

RunTopology runTopology(const TopologySnapshot& best, int first_observation) {
  RunTopology t;
  for (const TopologyNode& node : best.nodes) {
    if (node.places.empty()) continue;
    NodeInfo& n = t.nodes[node.id];
    for (std::size_t i = 0; i < node.places.size(); ++i) {
      if (node.places[i] < first_observation) {
        n.earlier_places.push_back(node.places[i]);
      } else {
        n.places.push_back(node.places[i] - first_observation);
        n.representative_frames.push_back(node.representative_frames[i]);
      }
    }
  }
  for (const TopologyEdge& edge : best.edges) t.edges[{edge.from, edge.to}] = edge.count;
  return t;
}

/// topology.json: the best topology, the final estimate and the history of the filter steps.
void writeTopologyJson(const fs::path& out_dir, const RunTopology& topology,
                       const TopologyEstimate& final_estimate, int particles, int first_observation,
                       const std::vector<MappedPlace>& steps) {
  TopologyFile file;
  file.probability = final_estimate.best.probability;
  file.particles = particles;
  TopologyFile::Estimate& e = file.estimate.emplace();
  e.current_node = final_estimate.current_node;
  e.current_node_probability = final_estimate.current_node_probability;
  e.effective_sample_size = final_estimate.effective_sample_size;
  e.distinct_topologies = final_estimate.distinct_topologies;
  e.earlier_places = first_observation;
  for (const TopologyHypothesis& h : final_estimate.alternatives)
    e.alternatives.push_back(TopologyFile::Alternative{h.probability, h.node_count, h.first_difference});
  for (const auto& [node, info] : topology.nodes) {
    TopologyFile::Node& n = file.nodes.emplace_back();
    n.id = node;
    for (std::int64_t p : info.places) n.places.push_back(static_cast<int>(p));
    n.representative_frames = info.representative_frames;
    for (std::int64_t p : info.earlier_places) n.earlier_places.push_back(static_cast<int>(p));
  }
  for (const auto& [edge, count] : topology.edges)
    file.edges.push_back(TopologyFile::Edge{edge.first, edge.second, count});
  for (const MappedPlace& s : steps) {
    TopologyFile::Step& step = file.history.emplace_back();
    step.place = static_cast<int>(s.place.index);
    step.node = s.estimate.current_node;
    step.probability = s.estimate.current_node_probability;
    step.best_topology_probability = s.estimate.best.probability;
    step.effective_sample_size = s.estimate.effective_sample_size;
  }
  writeTopology(out_dir, file);
}

/// The best topology in Graphviz' language, the current node highlighted.
std::string topologyDot(const RunTopology& topology, const TopologyEstimate& final_estimate) {
  std::ostringstream dot;
  dot << "digraph topology {\n  graph [label=\"most probable topology, p = " << std::setprecision(3)
      << final_estimate.best.probability << "\", labelloc=t];\n  node [shape=circle, style=filled, "
      << "fillcolor=\"#dde8f5\", fontname=\"Helvetica\"];\n  edge [fontname=\"Helvetica\", fontsize=10];\n";
  for (const auto& [node, info] : topology.nodes) {
    dot << "  n" << node << " [label=\"" << node << "\\nplaces";
    for (std::size_t i = 0; i < info.places.size(); ++i) dot << (i == 0 ? " " : ",") << info.places[i];
    if (!info.earlier_places.empty()) dot << "\\n(+" << info.earlier_places.size() << " earlier)";
    dot << "\"" << (node == final_estimate.current_node ? ", fillcolor=\"#f5c542\"" : "") << "];\n";
  }
  for (const auto& [edge, count] : topology.edges) {
    dot << "  n" << edge.first << " -> n" << edge.second << " [label=\"" << count << "\"];\n";
  }
  dot << "}\n";
  return dot.str();
}

/// topology.dot, and topology.svg and .png drawn from it when Graphviz' `dot` is installed (a warning,
/// not an error, when it fails).
void writeTopologyDrawings(const fs::path& out_dir, const std::string& dot) {
  {
    OutputFile out = openOutput(out_dir / "topology.dot");
    out << dot;
    out.commit();
  }
  if (!programOnPath("dot")) {
    std::cerr << "map: Graphviz `dot` not found: wrote topology.dot only\n";
    return;
  }
  const std::string dot_file = (out_dir / "topology.dot").string();
  for (const char* format : {"svg", "png"}) {
    // Drawn to a temporary name and renamed only when dot succeeded: a failing dot (a full disk) leaves
    // the earlier drawing, never a truncated one, under the real name.
    const fs::path final_path = out_dir / (std::string("topology.") + format);
    const fs::path temporary = out_dir / (std::string(".topology.") + format + ".tmp");
    const std::vector<std::string> command = {"dot", std::string("-T") + format, dot_file, "-o",
                                              temporary.string()};
    std::error_code error;
    if (runProgram(command) != 0) {
      std::cerr << "map: warning: `dot -T" << format << " " << shellQuote(dot_file) << " -o "
                << shellQuote(temporary.string()) << "` failed; " << final_path.string() << " not written\n";
      fs::remove(temporary, error);
    } else if (fs::rename(temporary, final_path, error); error) {
      std::cerr << "map: warning: cannot rename " << temporary.string() << " to " << final_path.string()
                << ": " << error.message() << "\n";
      fs::remove(temporary, error);
    }
  }
}

/// The run in one line on stdout, or one JSON object with --json.
void printSummary(const MapOptions& o, const SegmentationRun& all, std::size_t nodes,
                  const TopologyEstimate& final_estimate, const fs::path& out_dir) {
  if (o.json) {
    JsonWriter json(std::cout);
    json.beginObject()
        .field("frames", all.frames.size())
        .field("places", all.places.size())
        .field("dropped_places", all.dropped_places.size())
        .field("nodes", nodes)
        .field("best_topology_probability", final_estimate.best.probability)
        .field("current_node", final_estimate.current_node)
        .field("current_node_probability", final_estimate.current_node_probability)
        .field("out", out_dir.string())
        .endObject();
    std::cout << "\n" << std::flush;
    return;
  }
  std::printf(
      "%zu frames -> %zu places mapped (%zu dropped) -> %zu nodes; best topology p = %.3f, current node %d "
      "p = %.3f; wrote %s\n",
      all.frames.size(), all.places.size(), all.dropped_places.size(), nodes, final_estimate.best.probability,
      final_estimate.current_node, final_estimate.current_node_probability, out_dir.string().c_str());
}

/// `toposlam map`: set up the stages, run every source through them, save the map, write the run folder.
void runMap(const MapOptions& o) {
  if (o.sources.empty()) throw std::invalid_argument("map: give at least one SOURCE (e.g. images:DIR)");
  DaemonConfig config = commandConfig(o.config);
  std::optional<MotionReplay> motion = openMotion(o.motion, o.sources.size(), "map", config.segmentation);
  const FiedlerSegmenterConfig& segmenter_config = config.segmentation;
  const fs::path out_dir(o.out);
  createRunFolder(o.out);
  const fs::path map_path = out_dir / "map.tsm";
  try {
    MapStore::checkWritable(map_path);  // found out now, not after the run
  } catch (const MapStoreError& e) {
    throw ConfigError(std::string("map: ") + e.what());
  }
  const MapLock map_lock = lockRunFolderMap(map_path, o.out);

  // The filter steps run to their end before the next frame, so the budget's clock is never read for a
  // decision (ParticleFilterTopologyStage::advance with an infinite budget).
  const ManualClock clock;
  // toposlamd's stages (stage_assembly.hpp), on this thread; no thumbnails: no place events offline.
  StageAssembly stages(config, clock, nullptr, Thumbnails::None);
  const VpackConfig& vpack = config.fingerprint;
  const NgramSimilarity& similarity = stages.similarity();
  const SequenceEvidenceConfig& evidence = config.sequence_evidence;
  ParticleFilterTopologyStage& topology = stages.topology();
  const auto settings_for = [&](const std::string& uri) { return mapSettingsOf(config, config.topology, uri); };
  const bool localizing = config.map.mode == MapMode::Localize;
  if (localizing && o.resume.empty())
    throw ConfigError("map: map.mode is localize (--localize-only): give the map to localise in with --resume MAP");
  StartingFilter start;
  if (!o.resume.empty()) start = resumedFilter(o, topology, similarity, settings_for, localizing);
  if (localizing) {
    topology.startLocalizing(nodeLocalizerConfig(config.similarity, config.map.localize));
    std::cerr << "map: localising in " << o.resume << " (" << topology.topology().nodes.size()
              << " nodes); it is not changed, and the run folder gets no map.tsm\n";
  }
  const TopologyParticleFilter& filter = topology.filter();
  const int first_observation = filter.observationCount();

  // Thumbnails are the daemon's (place events); the offline run keeps none.
  FiedlerSegmentationStage& segmentation_stage = stages.segmentation();
  OfflineRunner runner(stages.fingerprint(), segmentation_stage, &topology);
  Traversals traversals =
      traverseSources(o, runner, segmentation_stage, motion, start.origins, start.run_number,
                      !evidence.frame_revisits);
  if (motion) std::cerr << motionSummary(segmentation_stage, o.motion, "map") << "\n";
  const SegmentationRun& all = runner.run();
  if (all.frames.empty())
    throw std::runtime_error("map: the sources gave no usable frames (" + std::to_string(traversals.refused.total()) +
                             " refused)");
  // The map first: it is the run's work and what --resume continues. A report file that cannot be
  // written afterwards (a full disk) is still an error, but no longer takes the map down with it.
  const MapSettings made_with =
      mapSettingsOf(config, filter.config(), o.sources.front());  // the first traversal's source
  finishRunOrigins(start.origins, start.run_number, all);
  if (!localizing)
    MapStore::writeAtomically(map_path, MapStore::encode(filter, encodeMapApplicationData(start.origins), made_with,
                                                         topology.views()));

  // The most probable topology decides every place's node.
  const TopologyEstimate final_estimate = filter.estimate(3);
  const std::vector<std::int64_t> place_nodes = runner.placeNodes();
  writeRunSettings(out_dir, o, config.preset, vpack, segmenter_config, filter.config(), evidence);
  {
    std::vector<std::string> uris;
    for (const std::string& uri : o.sources) uris.push_back(absoluteSourceUri(uri));
    writeSources(out_dir, uris);
  }
  std::vector<FrameRecord> frame_rows = frameRowsWithLoopClosures(
      runner, place_nodes, traversals.frame_fingerprints, similarity, evidence.frame_revisits, o.loop_min_gap);
  if (localizing) {  // every frame's own answer, as toposlamd publishes it in place_t
    const std::vector<OfflineRunner::FrameNode>& answers = runner.frameNodes();
    for (std::size_t f = 0; f < frame_rows.size() && f < answers.size(); ++f) {
      frame_rows[f].node = answers[f].node;
      frame_rows[f].node_probability = answers[f].probability;
    }
  }
  traversals.frame_fingerprints.clear();
  writeFrames(out_dir, frame_rows, FrameColumns::WithLoopClosures);
  writePlaces(out_dir, placeRows(all.places, place_nodes));
  writeDroppedPlaces(out_dir, placeRows(all.dropped_places));
  writeTiming(out_dir, traversals.timing);
  writeLambda2Plot(out_dir, all, segmenter_config,
                   "Fiedler value over " + std::to_string(o.sources.size()) + " source(s)");

  const RunTopology best = runTopology(topology.topology(), first_observation);
  writeTopologyJson(out_dir, best, final_estimate, filter.config().particles, first_observation,
                    runner.steps());
  writeTopologyDrawings(out_dir, topologyDot(best, final_estimate));
  printSummary(o, all, best.nodes.size(), final_estimate, out_dir);
}

}  // namespace

void addMapCommand(CLI::App& app) {
  auto options = std::make_shared<MapOptions>();
  auto* cmd = app.add_subcommand(
      "map", "Offline topological SLAM: segmentation plus the particle filter over topologies");
  cmd->add_option("sources", options->sources,
                  "Frame sources (images:DIR, video:FILE, sim:..., or a folder), "
                  "processed one after another as consecutive traversals")
      ->required();
  cmd->add_option("--out", options->out, "Output run folder")->required();
  cmd->add_flag("--json", options->json, "Print the summary as one JSON object (frames, places, nodes, probabilities)");
  cmd->add_flag("--quiet", options->quiet, "No progress and no per-place lines on stderr (warnings and errors stay)");
  addConfigOptions(*cmd, options->config);
  addSegmentationOptions(*cmd, options->config);
  ConfigOptions& c = options->config;
  addFlagAlias(*cmd, c, "--localize-only", "map.mode=localize",
               "= --set map.mode=localize: localise every frame in the map given with --resume, which is never "
               "changed (frames.csv's node is each frame's own answer; no map.tsm is written)");
  addKeyAlias(*cmd, c, "--particles", "topology.particles");
  addKeyAlias(*cmd, c, "--alpha", "topology.alpha");
  addKeyAlias(*cmd, c, "--seed", "topology.seed");
  addKeyAlias(*cmd, c, "--max-representatives", "topology.max_representatives_per_node");
  addKeyAlias(*cmd, c, "--likelihood", "topology.likelihood");
  addKeyAlias(*cmd, c, "--relative-slope", "topology.relative_slope");
  addKeyAlias(*cmd, c, "--relative-offset", "topology.relative_offset");
  addKeyAlias(*cmd, c, "--relative-sigma-floor", "topology.relative_sigma_floor");
  addKeyAlias(*cmd, c, "--new-node-entropy", "topology.new_node_entropy");
  addKeyAlias(*cmd, c, "--new-node-probability", "topology.new_node_probability");
  addKeyAlias(*cmd, c, "--new-node-likelihood-floor", "topology.new_node_likelihood_floor");
  addKeyAlias(*cmd, c, "--exhaustive-up-to", "topology.candidates.exhaustive_up_to");
  addKeyAlias(*cmd, c, "--candidates", "topology.candidates.candidates");
  addKeyAlias(*cmd, c, "--frame-loops", {"topology.sequence_evidence.frame_revisits"},
              {{"sequence", "true"}, {"visits", "false"}},
              "= --set topology.sequence_evidence.frame_revisits=true (sequence) or false (visits): frame-level loop "
              "closures in frames.csv by the sequence detector, online (docs/topology.md), or by the earlier visits "
              "of each frame's node (the thesis preset's)");
  addKeyAlias(*cmd, c, "--loop-min-gap-s", "topology.sequence_evidence.min_gap_s");
  addKeyAlias(*cmd, c, "--loop-memory-s", "topology.sequence_evidence.memory_s");
  addKeyAlias(*cmd, c, "--loop-scales", "topology.sequence_evidence.scales");
  addKeyAlias(*cmd, c, "--keyframe-interval-s", "topology.sequence_evidence.keyframe_interval_s");
  addKeyAlias(*cmd, c, "--loop-min-margin", "topology.sequence_evidence.min_margin");
  addKeyAlias(*cmd, c, "--loop-distinct-s", "topology.sequence_evidence.distinct_s");
  addKeyAlias(*cmd, c, "--sequence-evidence", "topology.sequence_evidence.weight");
  addKeyAlias(*cmd, c, "--sequence-evidence-min-score", "topology.sequence_evidence.min_score");
  addKeyAlias(*cmd, c, "--sequence-evidence-min-relative", "topology.sequence_evidence.min_relative");
  addKeyAlias(*cmd, c, "--sequence-evidence-min-share", "topology.sequence_evidence.min_share");
  addKeyAlias(*cmd, c, "--max-keypoints", "fingerprint.keypoints.max_keypoints");
  addKeyAlias(*cmd, c, "--histogram-weight", "similarity.histogram_weight");
  addKeyAlias(*cmd, c, "--histogram-gate", {"similarity.histogram_gate"}, {{"1", "true"}, {"0", "false"}},
              "= --set similarity.histogram_gate=true (1) or false (0): histograms as a gate or a weighted part");
  cmd->add_option("--loop-min-gap", options->loop_min_gap,
                  "Frame-level loop closures by visits (--frame-loops visits): detections at least this many frames "
                  "back")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--resume", options->resume, "Continue the map in this map.tsm");
  cmd->add_flag("--resume-other-source", options->resume_other_source,
                "With --resume: continue a map made from another source (refused otherwise)")
      ->needs("--resume");
  cmd->add_flag("--resume-other-settings", options->resume_other_settings,
                "With --resume: continue a map made with other settings (preset, segmentation, similarity, ...; "
                "refused otherwise). The keypoints must agree; the filter's settings come from the map")
      ->needs("--resume");
  addMotionOptions(*cmd, options->motion);
  cmd->callback([options] { runMap(*options); });
}

}  // namespace toposlam::cli
