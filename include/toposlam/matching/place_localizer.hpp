// Localisation of a query frame among K labelled places (thesis section 3.3.2, eq. 3.5-3.8, Algorithm
// 3.3). Each place has one or more reference fingerprints ("representatives").
//
//   1. For each place, match the query against every representative and keep the one with the highest
//      NgramSimilarity (the thesis keeps "the representative that provided the highest matching score").
//   2. For histograms and keypoints separately, and for n = 1, 2, 3, turn that representative's n-gram
//      counts x_{n,k} into a distribution with naive Bayes and Laplace smoothing (eq. 3.5):
//        p_n(L_k | O) = (x_{n,k} + alpha) / (sum_k x_{n,k} + alpha K),   alpha = 0.01.
//   3. Interpolate the three n-gram models with inverse-entropy weights (eq. 3.6-3.8):
//        H_n = -sum_k p_n log p_n,  w_n = (1/H_n) / sum_m (1/H_m),  p = sum_n w_n p_n.
//      Guard: H_n is floored at 1e-12, so a certain model (zero entropy, e.g. K = 1) gets the dominant
//      weight without a division by zero.
//   4. Final: p(L_k | O) proportional to p_hist(L_k | O) * p_kp(L_k | O), normalised.
// Degenerate inputs give uniform n-gram models (no subregions, no keypoints, nothing matched), which
// the inverse-entropy weights then mostly ignore; one place always gets probability 1.
//
// Thread-safety: immutable after construction; localize() is const and may run concurrently.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "toposlam/matching/ngram_similarity.hpp"

namespace toposlam {

struct PlaceLocalizerConfig {
  NgramSimilarityConfig similarity;  ///< matcher settings; also picks the best representative
  double laplace_alpha = 0.01;       ///< alpha_n of eq. 3.5, the same for every n (thesis: 0.01)
  /// x_{n,k} as in the thesis: the effective n-gram counts (false), or the counts divided by the
  /// n-grams the representative could have had (true), which stops long representatives winning by size.
  bool normalise_counts = false;
  std::string validate() const;
};

struct LabelledPlace {
  std::string label;
  std::vector<Fingerprint> references;  ///< at least one
};

/// One discrete distribution over the K places with its entropy (nats) and interpolation weight.
struct PlaceModel {
  std::vector<double> probabilities;
  double entropy = 0.0;
  double weight = 0.0;
};

/// The three n-gram models of one feature type and their inverse-entropy interpolation.
struct InterpolatedModel {
  std::array<PlaceModel, kMaxNgramOrder> ngrams;
  std::vector<double> probabilities;  ///< eq. 3.8
};

struct PlaceEvidence {
  int best_reference = -1;   ///< index into the place's references
  double similarity = 0.0;   ///< NgramSimilarity of that representative with the query
  NgramCounts counts;        ///< its n-gram counts
};

struct Localization {
  std::vector<PlaceEvidence> places;  ///< per place, in construction order
  InterpolatedModel histogram;
  InterpolatedModel keypoint;
  std::vector<double> probabilities;  ///< final, sums to 1
  int best_place = -1;
  double best_probability = 0.0;
};

class PlaceLocalizer {
 public:
  /// Throws std::invalid_argument when the config is invalid, there is no place, or a place has no
  /// reference fingerprint.
  PlaceLocalizer(const PlaceLocalizerConfig& config, std::vector<LabelledPlace> places);

  Localization localize(const Fingerprint& query) const;

  int placeCount() const { return static_cast<int>(places_.size()); }
  const LabelledPlace& place(int k) const { return places_.at(static_cast<std::size_t>(k)); }
  const PlaceLocalizerConfig& config() const { return config_; }

  /// Steps 2-3 on counts x[n-1][k] (exposed for tests): Laplace-smoothed models and their interpolation.
  static InterpolatedModel interpolate(const std::array<std::vector<double>, kMaxNgramOrder>& counts,
                                       double alpha);
  /// Shannon entropy in nats (0 log 0 = 0).
  static double entropy(const std::vector<double>& probabilities);

 private:
  PlaceLocalizerConfig config_;
  std::vector<LabelledPlace> places_;
  NgramSimilarity similarity_;
};

}  // namespace toposlam
