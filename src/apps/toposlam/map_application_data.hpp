// What `toposlam map` (and toposlamd) keep in a map file's application data (MapStore treats it as opaque
// bytes): per filter observation, the run and the frames it came from, so that a map alone can be turned
// back into a run folder (`toposlam export`, `map-info`, `report MAP`).
//
// Formats read (text, one record per line):
//   "toposlam-map-origins 2" (`map`, from this version):
//       run R FRAMES                                     frames run R segmented
//       traversal R START_FRAME START_TIME_S URI         one per source of run R, in order
//       place R REP FIRST LAST FIRST_TIME_S LAST_TIME_S KEYPOINTS END STEP_NODE NODE_PROBABILITY
//             BEST_TOPOLOGY_PROBABILITY EFFECTIVE_SAMPLE_SIZE        one per observation, in order
//   "toposlam-map-origins 1" (older `map`): "R REP" per observation.
//   "toposlamd-frames F0 F1 ..." (toposlamd): the representative frame of each observation.
// Anything else: observations of unknown origin. Frame numbers count from 0 within their run; -1 unknown.
//
// Thread-safety: plain functions and value types.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace toposlam::cli {

/// Where one observation of the map (one filter step, one kept place) came from.
struct ObservationOrigin {
  int run = 0;                             ///< 0 for the first `map` run, +1 per --resume; -1 unknown
  std::int64_t representative_frame = -1;  ///< frame number within that run
  std::int64_t first_frame = -1;           ///< the place's frames (-1: not recorded)
  std::int64_t last_frame = -1;
  double first_time_s = std::numeric_limits<double>::quiet_NaN();
  double last_time_s = std::numeric_limits<double>::quiet_NaN();
  int keypoints = 0;  ///< of the representative
  std::string end;    ///< why the place ended (placeEndName), empty when not recorded
  /// The filter's estimate when the place's step was done (topology.json's history): the current node, its
  /// probability (frames.csv's node_probability), the best topology's probability, the effective sample size.
  int step_node = -1;
  double node_probability = std::numeric_limits<double>::quiet_NaN();
  double best_topology_probability = std::numeric_limits<double>::quiet_NaN();
  double effective_sample_size = std::numeric_limits<double>::quiet_NaN();
};

/// One source of a run: where its frames start.
struct MapTraversal {
  int run = 0;
  std::int64_t start_frame = 0;
  double start_time_s = 0.0;
  std::string source;  ///< the source URI (absolute for image folders)
};

/// The application data of a map, decoded.
struct MapApplicationData {
  enum class Writer { Map, Daemon, Unknown };
  Writer writer = Writer::Unknown;
  std::vector<ObservationOrigin> origins;  ///< exactly one per observation
  std::vector<std::int64_t> run_frames;    ///< frames segmented per run (by run number); empty: not recorded
  std::vector<MapTraversal> traversals;
};

/// "toposlam map", "toposlamd" or "unknown".
const char* writerName(MapApplicationData::Writer writer);

/// The current format ("toposlam-map-origins 2").
std::string encodeMapApplicationData(const MapApplicationData& data);
/// Any of the formats above; `observations` (the filter's count) sets the number of origins (missing ones
/// unknown, extra ones dropped).
MapApplicationData decodeMapApplicationData(const std::string& text, int observations);

}  // namespace toposlam::cli
