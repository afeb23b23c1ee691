// Place recognition measured on its own (no segmentation, no filter): a similarity matrix between query
// frames and reference frames against a ground truth of which pairs show the same place
// (docs/evaluation.md, "Place recognition"). Three figures, as the visual place recognition literature
// reports them:
//   - AUC: probability that a random same-place candidate pair scores above a random different-place
//     one (ties count one half), over every evaluated candidate pair;
//   - top-1: share of the queries that have a true match among their candidates whose most similar
//     candidate is a true match;
//   - recall at 100 % precision: each query's most similar candidate is its detection, scored by the
//     similarity; detections are accepted from the highest score down, and this is the largest share of
//     the queries with a true match that are correctly detected before the first wrong detection.
// Two layouts: one sequence against its own past (reference = earlier frames, candidates at least
// min_gap frames back, the loop-closure setting), or a query set against a separate reference set.
//
// Pure functions and value types; no I/O (the loaders live in ground_truth.hpp). Thread-safe.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "toposlam/eval/metrics.hpp"
#include "toposlam/eval/ground_truth.hpp"

namespace toposlam::eval {

/// Which (query, reference) pairs are candidates and which of them show the same place.
struct RecognitionTruth {
  int queries = 0;
  int references = 0;
  /// queries x references, row-major: 1 same place, 0 different place, -1 not a candidate.
  std::vector<std::int8_t> state;
  std::int8_t at(int q, int r) const {
    return state[static_cast<std::size_t>(q) * static_cast<std::size_t>(references) + static_cast<std::size_t>(r)];
  }
};

/// One sequence against its own past: candidates of frame i are frames j <= i - min_gap (min_gap >= 1);
/// same place where the symmetric matrix says so.
RecognitionTruth sequenceTruthFromMatrix(const LoopClosureMatrix& matrix, int min_gap);
/// One sequence with per-frame rooms (-1 = doorway, never evaluated): same place = same room on another
/// visit (visitIds); the same visit is no candidate (nothing was recognised), other rooms are negatives.
RecognitionTruth sequenceTruthFromRooms(const std::vector<int>& rooms, int min_gap);
/// A query set against a reference set: every pair is a candidate; same place where `same` (queries x
/// references, row-major, non-zero) says so.
RecognitionTruth crossTruth(int queries, int references, const std::vector<std::uint8_t>& same);

/// Resolves a pairs file's frame names against frame paths: a name matches the path that equals it or
/// ends with "/" + name (so "ref/0000001.jpg" finds ".../corridor/ref/0000001.jpg"). Returns -1 when
/// none does; throws std::invalid_argument when several do.
int resolveFrameName(const std::string& name, const std::vector<std::string>& paths);

struct RecognitionScore {
  int queries = 0;             ///< queries with at least one candidate
  int queries_with_match = 0;  ///< of those, with at least one same-place candidate
  std::int64_t positive_pairs = 0, negative_pairs = 0;
  double auc = 0.0;   ///< NaN without both kinds of pairs
  double top1 = 0.0;  ///< NaN without queries_with_match
  int top1_correct = 0;
  double recall_at_full_precision = 0.0;
  double threshold_at_full_precision = 0.0;  ///< lowest accepted similarity at that recall
  double average_precision = 0.0;            ///< of the top-1 detections' precision-recall curve
  std::vector<PrPoint> curve;                ///< top-1 detections, one point per distinct score
  std::vector<int> best_reference;           ///< per query: its most similar candidate, -1 if none
  int detections = 0;                        ///< frameLoopClosures: frames with a detection
};

/// similarity: queries x references, row-major (the same layout as truth). Ties of the best candidate
/// go to the earlier reference. Throws std::invalid_argument when the sizes differ.
RecognitionScore scoreRecognition(const std::vector<float>& similarity, const RecognitionTruth& truth);

struct ScoredDetection {
  float score = 0.f;
  bool correct = false;
};
/// Fills score.curve, recall_at_full_precision, threshold_at_full_precision and average_precision from
/// detections (recall over score.queries_with_match).
void detectionCurve(std::vector<ScoredDetection> detections, RecognitionScore& score);

/// Frame-level loop closures of a run (one sequence, truth from sequenceTruthFrom*): frame f's detection
/// is match[f] (-1: none) with score_of_frame[f]. Precision, recall and recall at 100 % precision as the
/// loop-closure literature defines them: a detection is right when its frame is a true match at least
/// min_gap back; recall is over the frames that have one. top1 = right detections / frames with a
/// match (the recall at the lowest threshold); auc is NaN (there is no full matrix).
RecognitionScore frameLoopClosures(const std::vector<std::int64_t>& match, const std::vector<double>& score_of_frame,
                                   const RecognitionTruth& truth);

}  // namespace toposlam::eval
