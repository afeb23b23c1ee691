// The map on the desk: a map file (map.tsm, from `toposlam map` or toposlamd) opened without a run, for
// `toposlam map-info` (what it holds), `toposlam export` (a run folder that `report` and `eval` read) and
// `toposlam report MAP` (export to a temporary folder, then report).
//
// What an export holds is what the map holds: every observation (kept place) with its node in the most
// probable topology, the topology and the filter's estimate, the sources and settings; from `map`'s maps
// (application data version 2) also each place's frames and times, so frames.csv gives every frame its
// place and node as the original run did. Not in a map, so not in an export: frame names, lambda2, the
// frame-level matches, dropped places, timings and the filter's step history. A map that records only
// representative frames (toposlamd, older `map`) gives each place its representative frame alone.
//
// Thread-safety: plain functions; a DeskMap is one thread's.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "map_application_data.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/pipeline/clock.hpp"
#include "toposlam/run_folder/run_folder.hpp"
#include "toposlam/topology/map_store.hpp"

namespace toposlam::cli {

/// A map file, loaded: its filter (in a topology stage, for the most probable topology), its settings and
/// application data, and the file's facts.
struct DeskMap {
  std::filesystem::path path;
  std::uint64_t bytes = 0;
  std::string saved_utc;  ///< the file's modification time, "YYYY-mm-ddTHH:MM:SSZ"
  MapSettings settings;
  MapApplicationData origins;
  std::unique_ptr<NgramSimilarity> similarity;  ///< what the filter compares with (unused: no step is taken)
  std::unique_ptr<ManualClock> clock;
  std::unique_ptr<ParticleFilterTopologyStage> topology;
  TopologySnapshot best;     ///< the most probable topology (nodes with their observations)
  TopologyEstimate estimate;  ///< the filter's estimate, with up to 3 alternatives
};

/// True when `path` is a regular file that starts with a map file's magic.
bool looksLikeMapFile(const std::filesystem::path& path);

/// Loads `path`; throws std::runtime_error "<command>: <path>: <problem>" for a missing, unreadable, damaged
/// or truncated file (MapStore's reason), or one that is no map at all.
DeskMap openDeskMap(const std::filesystem::path& path, const std::string& command);

/// Nodes of the best topology that hold at least one observation.
int nodeCount(const DeskMap& map);

/// The method preset the map's settings agree with ("default", "thesis"), or "custom (N settings differ from
/// PRESET)" naming the closest; "unknown" when the map records none (made by an older toposlam).
std::string presetOf(const MapSettings& settings);

/// The run folder rows an export writes (see above).
struct ExportedRun {
  std::vector<FrameRecord> frames;
  std::vector<PlaceRecord> places;
  TopologyFile topology;
  std::vector<std::string> sources;
  RunSettings settings;
};
ExportedRun exportedRun(const DeskMap& map);

/// Writes exportedRun(map) into `dir` (created): frames.csv, places.csv, topology.json, source.txt,
/// settings.txt. Throws OutputFileError / std::runtime_error naming the file.
void writeExportedRun(const DeskMap& map, const std::filesystem::path& dir);

/// The filter's estimate as topology.json records it (`earlier_places`: observations of a resumed map).
TopologyFile::Estimate topologyFileEstimate(const TopologyEstimate& estimate, int earlier_places);

}  // namespace toposlam::cli
