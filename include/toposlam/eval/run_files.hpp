// Loaders for the files of a run folder (docs/run-folder.md) and for ground truth: labels.csv,
// frames.csv, places.csv, dropped_places.csv, topology.json, timing.csv, a loop-closure matrix image
// (samples_GT.bmp: pixel (x=j, y=i) non-zero = frame i shows the same place as frame j) and a CSV of
// loop-closure pairs (samples_GT_pairs.csv: `query_image,matching_images` with space-separated names).
//
// Every loader throws RunFileError with "<file>:<line>: <problem>" for malformed input, so a person
// can open the file at that line. Columns are found by header name (extra columns are ignored, order
// does not matter). Thread-safety: pure functions.
#pragma once

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace toposlam::eval {

class RunFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One row of labels.csv (ground truth from the simulator).
struct LabelRow {
  std::int64_t frame = 0;
  double time_s = 0.0;
  int room = -1;  ///< >= 0 a room; -1 "in a doorway" (no room)
  /// Which traversal of the route the frame is on (optional column `traversal`, written by `toposlam sim`):
  /// >= 0 and never decreasing down the file; -1 when the file has no such column.
  int traversal = -1;
  /// The camera's pose (optional columns x, y in metres and heading in radians, written by `toposlam sim`;
  /// all three or none): NaN when the file has none.
  double x = std::numeric_limits<double>::quiet_NaN();
  double y = std::numeric_limits<double>::quiet_NaN();
  double heading = std::numeric_limits<double>::quiet_NaN();
};

/// One row of frames.csv.
struct FrameRecord {
  std::int64_t frame = 0;
  double time_s = 0.0;
  std::string name;
  double lambda2 = std::numeric_limits<double>::quiet_NaN();  ///< NaN when empty
  int place = -1;
  int node = -1;
  double node_probability = std::numeric_limits<double>::quiet_NaN();  ///< NaN when absent
  std::int64_t match = -1;  ///< frame-level loop-closure detection (earlier frame), -1: none
  double match_score = 0.0;
};

/// One row of places.csv / dropped_places.csv.
struct PlaceRecord {
  int place = 0;
  int line = 0;  ///< line of places.csv / dropped_places.csv, for error messages
  std::int64_t first = 0, last = 0, representative = 0;
  int keypoints = 0;
  int node = -1;
};

struct TopologyNode {
  int id = 0;
  std::vector<int> places;
  std::vector<std::int64_t> representative_frames;  ///< -1: from an earlier (resumed) run
};

struct TopologyEdge {
  int from = 0, to = 0, count = 0;
};

/// One filter step (one kept place) of topology.json's history.
struct TopologyStep {
  int place = 0;
  int node = -1;
  double probability = 0.0;                ///< of the place's node assignment
  double best_topology_probability = 0.0;  ///< of the most probable topology after this step
  double effective_sample_size = 0.0;
};

struct TopologyFile {
  double probability = 0.0;
  int particles = 0;
  std::vector<TopologyNode> nodes;
  std::vector<TopologyEdge> edges;
  std::vector<TopologyStep> history;
};

struct TimingRow {
  std::int64_t frame = 0;
  double fingerprint_ms = 0.0, segment_ms = 0.0, filter_ms = 0.0;
};

/// A loop-closure ground-truth matrix: n x n, row-major, non-zero = same place. Symmetric after loading.
struct LoopClosureMatrix {
  int size = 0;
  std::vector<std::uint8_t> same;  ///< size*size
  bool at(int i, int j) const {
    return same[static_cast<std::size_t>(i) * static_cast<std::size_t>(size) + static_cast<std::size_t>(j)] !=
           0;
  }
};

/// Frame-name pairs from a pairs CSV; resolved to frame numbers against frames.csv by the caller.
struct NamedPair {
  std::string query;
  std::string match;
  int line = 0;  ///< line of the pairs file, for error messages
};

std::vector<LabelRow> loadLabels(const std::string& path);
std::vector<FrameRecord> loadFrames(const std::string& path);
std::vector<PlaceRecord> loadPlaces(const std::string& path);
TopologyFile loadTopology(const std::string& path);
std::vector<TimingRow> loadTiming(const std::string& path);
/// Any image OpenCV reads (BMP, PNG); must be square.
LoopClosureMatrix loadLoopClosureImage(const std::string& path);
std::vector<NamedPair> loadLoopClosurePairs(const std::string& path);

/// A CSV table with named columns (header line required); the building block of the loaders above.
struct CsvTable {
  std::string path;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<int> lines;  ///< the file line of each row (1-based)
  /// Column index by name, or -1; `required` throws naming the file and the missing column.
  int column(const std::string& name, bool required = true) const;
  /// Parses cell (row, column) as a number; throws "<file>:<line>: column '<c>': '<text>' is not a number".
  double number(std::size_t row, int column, bool allow_empty = false) const;
  std::int64_t integer(std::size_t row, int column) const;
};
CsvTable readCsv(const std::string& path);

}  // namespace toposlam::eval
