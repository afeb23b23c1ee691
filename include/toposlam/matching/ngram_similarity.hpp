// Pairwise similarity of two frames from their n-gram counts (thesis chapters 4 and 5 use it for the
// affinity matrix and the particle filter's likelihoods; NOTES.md "n-gram matching").
//
// For each feature type f (histograms, keypoints) and n = 1..3 with at least one possible n-gram:
//   r_f,n = count_f,n / possible_f,n            (in [0, 1]; "effective n-grams" over those the reference had)
//   S_f   = mean of r_f,n over the available n  (equal weights, no Bayes across places)
//   similarity = histogram_weight * S_hist + (1 - histogram_weight) * S_kp
// When the reference owns no keypoint at all, S_kp is undefined and similarity = S_hist (if the
// query has none but the reference does, S_kp = 0: the texture is missing). A reference without
// subregions gives 0. A frame compared with itself gives 1 up to rounding (identical letters match
// at d = 0 and every keypoint is its own best match).
//
// Thread-safety: const and re-entrant; the hot path allocates nothing (per-thread scratch).
#pragma once

#include <cstdint>
#include <string>

#include "toposlam/matching/ngram_matcher.hpp"
#include "toposlam/matching/similarity_measure.hpp"

namespace toposlam {

/// How the keypoint part S_kp is made from the n-gram counts.
enum class KeypointScoring : std::uint8_t {
  /// Thesis: mean over n of effective keypoint n-grams / possible n-grams of the reference.
  PossibleNgrams = 0,
  /// Real images (docs/matching.md): the verified keypoint matches that keep the subregion order (the
  /// most on one order-preserving alignment of letters, NgramCounts::aligned_matches) over
  /// min(reference keypoints, query keypoints). Frames with 1-2 letters score like any other.
  VerifiedMatches = 1,
};
const char* toString(KeypointScoring scoring);
/// Parses "possible-ngrams" or "verified-matches"; throws std::invalid_argument otherwise.
KeypointScoring parseKeypointScoring(const std::string& name);

struct NgramSimilarityConfig {
  NgramMatcherConfig matcher;
  /// Weight of the histogram part; the keypoint part gets 1 - this (default: plain mean of both).
  double histogram_weight = 0.5;
  KeypointScoring keypoint_scoring = KeypointScoring::PossibleNgrams;
  /// Histograms as a gate rather than a summand: similarity = S_kp x (1 - w + w S_hist), w =
  /// histogram_weight, so keypoint evidence between differently coloured places is scaled down and
  /// colour alone never makes a match (docs/matching.md). Off: the weighted sum (thesis).
  bool histogram_gate = false;
  /// A reference without keypoints is scored by its histograms alone (thesis reading). Off, its
  /// keypoint part is 0: a blank wall is no evidence of a place.
  bool histogram_only_fallback = true;
  std::string validate() const;
};

/// The parts of one similarity, for explanations (CLI, docs) and tests.
struct SimilarityBreakdown {
  NgramCounts counts;
  double histogram_part = 0.0;   ///< S_hist in [0, 1]
  double keypoint_part = 0.0;    ///< S_kp in [0, 1] (0 when unavailable)
  bool keypoint_part_available = false;
  double similarity = 0.0;
};

class NgramSimilarity : public SimilarityMeasure {
 public:
  /// Throws std::invalid_argument naming the bad key when the config is invalid.
  explicit NgramSimilarity(const NgramSimilarityConfig& config = {});

  double similarity(const Fingerprint& reference, const Fingerprint& query) const override;
  /// Same as similarity() with caller-provided scratch buffers.
  double similarity(const Fingerprint& reference, const Fingerprint& query, MatchScratch& scratch) const;
  /// 0.5 * (similarity(a, b) + similarity(b, a)), bit for bit, with one descriptor pass for both
  /// (NgramMatcher::countsBothWays).
  double symmetricSimilarity(const Fingerprint& a, const Fingerprint& b) const override;
  SimilarityBreakdown explain(const Fingerprint& reference, const Fingerprint& query) const;

  /// The normalisation above applied to counts computed elsewhere (e.g. by PlaceLocalizer).
  static SimilarityBreakdown fromCounts(const NgramCounts& counts, const NgramSimilarityConfig& config);

  const NgramMatcher& matcher() const { return matcher_; }
  const NgramSimilarityConfig& config() const { return config_; }

 private:
  NgramSimilarityConfig config_;
  NgramMatcher matcher_;
};

}  // namespace toposlam
