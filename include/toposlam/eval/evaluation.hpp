// Evaluates one run folder (docs/run-folder.md) against ground truth and formats the result as text
// tables (the `toposlam eval` output), eval.json and HTML tables (for `toposlam report`).
//
// Ground truth is one of: labels.csv (frame -> room, from the simulator), a loop-closure matrix image
// (samples_GT.bmp layout) or a CSV of loop-closure pairs (samples_GT_pairs.csv layout). Which measures
// can be computed depends on it: a matrix or pairs give only the loop-closure curve; labels give all.
//
// Thread-safety: plain functions and value types.
#pragma once

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "toposlam/eval/metrics.hpp"
#include "toposlam/eval/recognition.hpp"
#include "toposlam/eval/ground_truth.hpp"
#include "toposlam/run_folder/run_folder.hpp"

namespace toposlam::eval {

/// `count` traversals of equal length (count >= 1).
std::vector<std::int64_t> splitTraversals(std::int64_t frame_count, int count);

struct Truth {
  enum class Kind { Labels, Matrix, Pairs };
  Kind kind = Kind::Labels;
  std::string path;
  std::vector<LabelRow> labels;
  LoopClosureMatrix matrix;
  std::vector<NamedPair> pairs;
  /// Labels only: first frame of each traversal, from the labels' `traversal` column and one per labels file
  /// when several were concatenated; empty when the labels do not say (old labels.csv, one file).
  std::vector<std::int64_t> traversal_starts;
};

/// By content: a CSV whose header has `room` is labels.csv, any other CSV is a pairs file, anything else
/// is read as a matrix image. Labels with a `traversal` column set traversal_starts.
Truth loadTruth(const std::string& path);
/// Several truth files: labels files are concatenated in order (their first frames become the traversal
/// starts); a matrix or pairs file must come alone. Throws std::invalid_argument otherwise.
Truth loadTruth(const std::vector<std::string>& paths);

struct EvalOptions {
  int tolerance = 5;  ///< frames, for boundary matching
  int min_gap = -1;   ///< loop closures: pairs closer than this are ignored; -1 = auto
                      ///< (25, the segmentation window, for a matrix/pairs; 0 for labels)
  std::vector<double> thresholds = defaultThresholds();
  /// > 0: split the frames evenly into this many traversals when the labels do not say (no `traversal`
  /// column, one labels file); 0: one per source of `map` (time going back). Labels that say win.
  int traversals = 0;
};

struct EvalResult {
  std::string run_dir;
  std::string truth_path;
  std::string truth_kind;  ///< "labels", "matrix" or "pairs"
  int frames = 0;
  int places = 0;
  int dropped_places = 0;
  int traversals = 1;
  std::vector<std::int64_t> traversal_starts;  ///< first frame of each traversal used
  int min_gap = 0;
  std::optional<std::vector<LocalisationRow>> localisation;  ///< needs labels and a node per frame
  std::optional<PrCurve> loop_closure;                       ///< needs nodes (from `map`)
  /// Frame-level loop closures (each frame's detected earlier frame); needs frames.csv's match column.
  std::optional<RecognitionScore> frame_loop_closure;
  std::optional<BoundaryScore> boundaries;                   ///< needs labels
  std::optional<std::vector<TraversalCount>> places_per_traversal;
  std::optional<ConsistencyScore> consistency;
  std::optional<TopologyScore> topology;
  /// Place revisits judged by the camera's pose; needs nodes and labels with x, y, heading (the simulator's).
  std::optional<PlaceRevisitScore> place_revisits;
  /// The published frame matches judged by the camera's pose; needs frames.csv's match column and poses.
  std::optional<FrameMatchPoseScore> frame_matches_by_pose;
  std::vector<double> best_topology_probability;  ///< per filter step, from topology.json
  std::vector<std::string> notes;                 ///< why a measure is missing, etc.
};

/// Throws RunFileError (or std::invalid_argument) when the truth does not fit the run (frame counts,
/// unknown frame names in a pairs file).
EvalResult evaluate(const RunData& run, const Truth& truth, const EvalOptions& options);

/// Per-frame node probability: the history probability of the frame's place (1 when unknown).
std::vector<double> frameNodeProbabilities(const RunData& run);
/// Cuts between segmented places (kept and dropped): the first frame of each place after a traversal start.
std::vector<std::int64_t> predictedCuts(const RunData& run,
                                        const std::vector<std::int64_t>& traversal_starts);

void writeEvalJson(std::ostream& out, const EvalResult& result);
std::string formatEvalText(const EvalResult& result);
std::string formatEvalHtml(const EvalResult& result);

}  // namespace toposlam::eval
