// The run folder (docs/run-folder.md): the one layout every offline command writes and `eval` and `report`
// read. This module owns the format: the file names, every file's header and columns, and both directions,
// writing (through platform/os's OutputFile: temporary name, checked writes, rename) and reading. Its users:
// `toposlam map` and `segment` (frames.csv, places.csv, dropped_places.csv, topology.json, timing.csv,
// lambda2.svg, source.txt, settings.txt), `toposlam sim` (labels.csv), the LCM-log converter, `eval` and
// `report` (loadRun). Each row type is both what a writer takes and what the loader returns, so a file
// written and read back gives the rows written.
//
// Readers throw RunFileError with "<file>:<line>: <problem>" for malformed input (a damaged or truncated
// file), so a person can open the file at that line. Columns are found by header name (extra columns are
// ignored, order does not matter). Writers throw OutputFileError naming the file (a full disk, no such
// folder). Thread-safety: plain functions and value types.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "toposlam/core/svg_plot.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"
#include "toposlam/segmentation/segmentation_run.hpp"

namespace toposlam {

/// The files of a run folder.
namespace run_files {
inline constexpr const char* kFrames = "frames.csv";
inline constexpr const char* kPlaces = "places.csv";
inline constexpr const char* kDroppedPlaces = "dropped_places.csv";
inline constexpr const char* kTopology = "topology.json";
inline constexpr const char* kTiming = "timing.csv";
inline constexpr const char* kLambda2Plot = "lambda2.svg";
inline constexpr const char* kSources = "source.txt";
inline constexpr const char* kSettings = "settings.txt";
inline constexpr const char* kLabels = "labels.csv";
inline constexpr const char* kFramesFolder = "frames";  ///< the run's own frames (sim, LCM-log thumbnails)
}  // namespace run_files

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
  // The loop-closure columns (`map`; FrameColumns::WithLoopClosures):
  double node_probability = std::numeric_limits<double>::quiet_NaN();  ///< NaN when empty or absent
  std::int64_t match = -1;  ///< frame-level loop-closure detection (earlier frame), -1: none
  double match_score = 0.0;  ///< written only with a match
};

/// frames.csv's columns: `frame,time,name,lambda2,place,node` (segment, the LCM-log converter), those and
/// `node_probability` (a map file's export: no frame-level matches), or those and
/// `node_probability,match,match_score` (map).
enum class FrameColumns { Segmentation, WithNodeProbability, WithLoopClosures };

/// One row of places.csv / dropped_places.csv.
struct PlaceRecord {
  int place = 0;
  int line = 0;  ///< line of places.csv / dropped_places.csv when read, for error messages (not written)
  std::int64_t first = 0, last = 0, representative = 0;
  int keypoints = 0;
  int node = -1;
  /// Why the place ended (placeEndName: valley, valley_at_doorway, doorway, interrupted_valley,
  /// stream_end); empty when not known (a folder made from an LCM log, or written before the column).
  std::string end;
};

/// topology.json: the most probable topology, and with `map` the filter's estimate at the end.
struct TopologyFile {
  struct Node {
    int id = 0;
    std::vector<int> places;
    std::vector<std::int64_t> representative_frames;  ///< -1: from an earlier (resumed) run
    std::vector<int> earlier_places;  ///< observations of a resumed map, before this run (written when any)
  };
  struct Edge {
    int from = 0, to = 0, count = 0;
  };
  /// One filter step (one kept place) of the history.
  struct Step {
    int place = 0;
    int node = -1;
    double probability = 0.0;  ///< of the place's node assignment
    std::optional<double> best_topology_probability;  ///< after this step (`map`)
    std::optional<double> effective_sample_size;      ///< (`map`)
    std::optional<bool> is_new;                       ///< the place event's (the LCM-log converter)
  };
  struct Alternative {
    double probability = 0.0;
    int nodes = 0;
    int first_difference = -1;  ///< observation number
  };
  /// The filter's estimate at the end of a `map` run (absent from the LCM-log converter's file).
  struct Estimate {
    int current_node = -1;
    double current_node_probability = 0.0;
    double effective_sample_size = 0.0;
    int distinct_topologies = 0;
    int earlier_places = 0;  ///< observations of the resumed map
    std::vector<Alternative> alternatives;
  };
  double probability = 0.0;
  int particles = 0;
  std::optional<Estimate> estimate;
  std::vector<Node> nodes;
  std::vector<Edge> edges;
  std::vector<Step> history;
};

/// One row of timing.csv, milliseconds.
struct TimingRow {
  std::int64_t frame = 0;
  double fingerprint_ms = 0.0, segment_ms = 0.0;
  std::optional<double> filter_ms;  ///< empty column when the command has no filter (`segment`)
};

/// settings.txt: what a run was made with, "key = value" lines in file order.
using RunSettings = std::vector<std::pair<std::string, std::string>>;

/// A CSV table with named columns (header line required); the building block of the loaders.
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

// ---------------------------------------------------------------------------------------------------
// Reading

std::vector<LabelRow> loadLabels(const std::string& path);
std::vector<FrameRecord> loadFrames(const std::string& path);
std::vector<PlaceRecord> loadPlaces(const std::string& path);
TopologyFile loadTopology(const std::string& path);
std::vector<TimingRow> loadTiming(const std::string& path);
/// source.txt's URIs, one per traversal (blank lines skipped); empty when the file is missing.
std::vector<std::string> loadSources(const std::filesystem::path& dir);
/// settings.txt's pairs (`#` lines skipped); empty when the file is missing. Throws RunFileError naming the
/// line that is no "key = value".
RunSettings loadSettings(const std::filesystem::path& dir);

/// Everything a run folder holds that eval and report read. Only frames.csv is required.
struct RunData {
  std::string dir;
  std::vector<FrameRecord> frames;
  std::vector<PlaceRecord> places;          ///< places.csv (kept places), empty when absent
  std::vector<PlaceRecord> dropped_places;  ///< dropped_places.csv, empty when absent
  std::optional<TopologyFile> topology;     ///< topology.json (from `map`)
  std::vector<TimingRow> timing;            ///< timing.csv
  bool has_frame_matches = false;           ///< frames.csv has the match columns of `map`
  std::vector<std::string> sources;         ///< source.txt: the run's source URIs, one per traversal
  RunSettings settings;                     ///< settings.txt (`map`, the LCM-log converter)
  /// First frame of each traversal: frame 0, then every frame whose time is below the previous frame's
  /// (a new source of `map`), unless set explicitly (evenly split by eval's splitTraversals).
  std::vector<std::int64_t> traversal_starts;
};

/// Throws RunFileError naming the file (and line) when the folder or frames.csv is missing, a file is
/// malformed, or a place lies outside frames.csv (a damaged run folder).
RunData loadRun(const std::string& dir);

// ---------------------------------------------------------------------------------------------------
// Writing. Every writer replaces its file whole (temporary name, checked, renamed).

/// Creates the run folder; throws std::runtime_error naming it when it cannot.
void createRunFolder(const std::filesystem::path& dir);

/// frames.csv rows of an offline run's segmentation: each frame with its kept place and that place's node
/// (`place_nodes[p]`; missing or no vector: -1), no loop-closure columns filled.
std::vector<FrameRecord> frameRows(const SegmentationRun& run, const std::vector<std::int64_t>& place_nodes = {});
/// places.csv / dropped_places.csv rows: a kept place's node is `place_nodes[p]` (else -1), a dropped one's -1.
std::vector<PlaceRecord> placeRows(const std::vector<SegmentedPlace>& places,
                                   const std::vector<std::int64_t>& place_nodes = {});

/// frames.csv. Names are quoted as CSV fields when they hold a comma, a quote or a line break or start or
/// end with white space (quoteCsvField).
void writeFrames(const std::filesystem::path& dir, const std::vector<FrameRecord>& rows, FrameColumns columns);
/// places.csv: `place,first,last,representative,keypoints,node,end`.
void writePlaces(const std::filesystem::path& dir, const std::vector<PlaceRecord>& rows);
/// dropped_places.csv: the same columns.
void writeDroppedPlaces(const std::filesystem::path& dir, const std::vector<PlaceRecord>& rows);
void writeTopology(const std::filesystem::path& dir, const TopologyFile& topology);
/// timing.csv: `frame,fingerprint_ms,segment_ms,filter_ms`.
void writeTiming(const std::filesystem::path& dir, const std::vector<TimingRow>& rows);
/// source.txt: one URI per line (the caller makes image folders absolute).
void writeSources(const std::filesystem::path& dir, const std::vector<std::string>& uris);
void writeSettings(const std::filesystem::path& dir, const RunSettings& settings);

/// lambda2 over time with the kept places' borders as dashed lines (grey for dropped ones) and the
/// valley detector's gamma as a dotted reference (thesis Figure 4.10). x is the frame number.
SvgPlot lambda2Plot(const SegmentationRun& run, const FiedlerSegmenterConfig& config, const std::string& title);
/// lambda2.svg: lambda2Plot drawn.
void writeLambda2Plot(const std::filesystem::path& dir, const SegmentationRun& run,
                      const FiedlerSegmenterConfig& config, const std::string& title);

/// labels.csv, written a row at a time (`toposlam sim` renders frame after frame): the header line and one
/// row (`frame,time,room,x,y,heading,traversal`), each with its line break.
std::string labelsHeader();
std::string labelsRow(const LabelRow& row);

}  // namespace toposlam
