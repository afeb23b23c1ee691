// Pairwise similarity of two frames from their n-gram counts: see ngram_similarity.hpp.
#include "toposlam/matching/ngram_similarity.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace toposlam {
namespace {

// Mean over the n with at least one possible n-gram of count / possible; false when none is possible.
bool meanNormalisedCount(const std::array<double, kMaxNgramOrder>& count,
                         const std::array<int, kMaxNgramOrder>& possible, double& mean) {
  double sum = 0.0;
  int models = 0;
  for (int n = 0; n < kMaxNgramOrder; ++n) {
    if (possible[n] <= 0) continue;
    sum += std::clamp(count[n] / possible[n], 0.0, 1.0);
    ++models;
  }
  mean = models > 0 ? sum / models : 0.0;
  return models > 0;
}

// Verified-match keypoint part (KeypointScoring::VerifiedMatches): the verified matches on the best
// order-preserving letter alignment over the smaller keypoint count; false when either frame has no
// keypoint (the part is then 0).
bool verifiedKeypointPart(const NgramCounts& c, double& part) {
  const int smaller = std::min(c.reference_keypoints, c.query_keypoints);
  part = 0.0;
  if (smaller <= 0) return false;
  part = std::clamp(static_cast<double>(c.aligned_matches) / smaller, 0.0, 1.0);
  return true;
}

}  // namespace

const char* toString(KeypointScoring scoring) {
  return scoring == KeypointScoring::VerifiedMatches ? "verified-matches" : "possible-ngrams";
}

KeypointScoring parseKeypointScoring(const std::string& name) {
  if (name == "possible-ngrams") return KeypointScoring::PossibleNgrams;
  if (name == "verified-matches") return KeypointScoring::VerifiedMatches;
  throw std::invalid_argument("keypoint scoring '" + name + "': expected possible-ngrams or verified-matches");
}

std::string NgramSimilarityConfig::validate() const {
  if (std::string problem = matcher.validate(); !problem.empty()) return "matcher." + problem;
  if (!(histogram_weight >= 0.0 && histogram_weight <= 1.0))
    return "histogram_weight: must be in [0, 1] (0.5 = mean of histogram and keypoint parts)";
  return "";
}

NgramSimilarity::NgramSimilarity(const NgramSimilarityConfig& config)
    : config_(config), matcher_(config.matcher) {
  const std::string problem = config_.validate();
  if (!problem.empty()) throw std::invalid_argument("similarity config: " + problem);
}

SimilarityBreakdown NgramSimilarity::fromCounts(const NgramCounts& counts, const NgramSimilarityConfig& config) {
  SimilarityBreakdown b;
  b.counts = counts;
  const double histogram_weight = config.histogram_weight;
  const bool histogram_available = meanNormalisedCount(counts.histogram, counts.histogram_possible, b.histogram_part);
  if (config.keypoint_scoring == KeypointScoring::VerifiedMatches)
    b.keypoint_part_available = verifiedKeypointPart(counts, b.keypoint_part);
  else
    b.keypoint_part_available = meanNormalisedCount(counts.keypoint, counts.keypoint_possible, b.keypoint_part);
  if (!histogram_available) {
    b.similarity = 0.0;  // no subregions in the reference: nothing to compare
  } else if (!b.keypoint_part_available && config.histogram_only_fallback) {
    b.similarity = b.histogram_part;
  } else {
    b.similarity = config.histogram_gate
                       ? b.keypoint_part * (1.0 - histogram_weight + histogram_weight * b.histogram_part)
                       : histogram_weight * b.histogram_part + (1.0 - histogram_weight) * b.keypoint_part;
  }
  b.similarity = std::clamp(b.similarity, 0.0, 1.0);
  return b;
}

double NgramSimilarity::similarity(const Fingerprint& reference, const Fingerprint& query) const {
  return fromCounts(matcher_.counts(reference, query), config_).similarity;
}

double NgramSimilarity::similarity(const Fingerprint& reference, const Fingerprint& query,
                                   MatchScratch& scratch) const {
  return fromCounts(matcher_.counts(reference, query, &scratch), config_).similarity;
}

double NgramSimilarity::symmetricSimilarity(const Fingerprint& a, const Fingerprint& b) const {
  const auto [forward, backward] = matcher_.countsBothWays(a, b);
  return 0.5 * (fromCounts(forward, config_).similarity + fromCounts(backward, config_).similarity);
}

SimilarityBreakdown NgramSimilarity::explain(const Fingerprint& reference, const Fingerprint& query) const {
  return fromCounts(matcher_.counts(reference, query), config_);
}

}  // namespace toposlam
