// Localisation among labelled places by n-gram models (thesis section 3.3.2): see place_localizer.hpp.
#include "toposlam/matching/place_localizer.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace toposlam {
namespace {

constexpr double kEntropyFloor = 1e-12;  // nats; keeps 1/H finite for a certain model

void normalise(std::vector<double>& values) {
  const double sum = std::accumulate(values.begin(), values.end(), 0.0);
  if (sum > 0.0 && std::isfinite(sum)) {
    for (double& v : values) v /= sum;
  } else {
    std::fill(values.begin(), values.end(), values.empty() ? 0.0 : 1.0 / static_cast<double>(values.size()));
  }
}

}  // namespace

std::string PlaceLocalizerConfig::validate() const {
  if (std::string problem = similarity.validate(); !problem.empty()) return "similarity." + problem;
  if (!(laplace_alpha > 0.0 && std::isfinite(laplace_alpha)))
    return "laplace_alpha: must be > 0 (thesis: 0.01; keep it much smaller than 1)";
  return "";
}

PlaceLocalizer::PlaceLocalizer(const PlaceLocalizerConfig& config, std::vector<LabelledPlace> places)
    : config_(config), places_(std::move(places)), similarity_(config.similarity) {
  if (std::string problem = config_.validate(); !problem.empty())
    throw std::invalid_argument("localizer config: " + problem);
  if (places_.empty()) throw std::invalid_argument("localizer: no places to localise against");
  for (const LabelledPlace& p : places_) {
    if (p.references.empty())
      throw std::invalid_argument("localizer: place '" + p.label + "' has no reference fingerprint");
  }
}

double PlaceLocalizer::entropy(const std::vector<double>& probabilities) {
  double h = 0.0;
  for (double p : probabilities) {
    if (p > 0.0) h -= p * std::log(p);
  }
  return std::max(0.0, h);
}

InterpolatedModel PlaceLocalizer::interpolate(const std::array<std::vector<double>, kMaxNgramOrder>& counts,
                                              double alpha) {
  InterpolatedModel model;
  const std::size_t k_places = counts[0].size();
  double inverse_sum = 0.0;
  for (int n = 0; n < kMaxNgramOrder; ++n) {
    PlaceModel& m = model.ngrams[n];
    m.probabilities.assign(k_places, 0.0);
    double total = 0.0;
    for (std::size_t k = 0; k < k_places; ++k) total += std::max(0.0, counts[n].at(k));
    const double denominator = total + alpha * static_cast<double>(k_places);
    for (std::size_t k = 0; k < k_places; ++k)
      m.probabilities[k] = (std::max(0.0, counts[n][k]) + alpha) / denominator;  // eq. 3.5
    m.entropy = entropy(m.probabilities);                                      // eq. 3.6
    m.weight = 1.0 / std::max(m.entropy, kEntropyFloor);
    inverse_sum += m.weight;
  }
  model.probabilities.assign(k_places, 0.0);
  for (int n = 0; n < kMaxNgramOrder; ++n) {
    PlaceModel& m = model.ngrams[n];
    m.weight /= inverse_sum;  // eq. 3.7
    for (std::size_t k = 0; k < k_places; ++k) model.probabilities[k] += m.weight * m.probabilities[k];  // 3.8
  }
  normalise(model.probabilities);
  return model;
}

Localization PlaceLocalizer::localize(const Fingerprint& query) const {
  Localization result;
  const std::size_t k_places = places_.size();
  result.places.resize(k_places);
  const bool verified = config_.similarity.keypoint_scoring == KeypointScoring::VerifiedMatches;
  std::array<std::vector<double>, kMaxNgramOrder> histogram_counts;
  std::array<std::vector<double>, kMaxNgramOrder> keypoint_counts;
  for (int n = 0; n < kMaxNgramOrder; ++n) {
    histogram_counts[n].assign(k_places, 0.0);
    keypoint_counts[n].assign(k_places, 0.0);
  }
  for (std::size_t k = 0; k < k_places; ++k) {
    PlaceEvidence& evidence = result.places[k];
    const std::vector<Fingerprint>& references = places_[k].references;
    for (std::size_t r = 0; r < references.size(); ++r) {
      const NgramCounts counts = similarity_.matcher().counts(references[r], query);
      const double s = NgramSimilarity::fromCounts(counts, config_.similarity).similarity;
      if (evidence.best_reference < 0 || s > evidence.similarity) {
        evidence.best_reference = static_cast<int>(r);
        evidence.similarity = s;
        evidence.counts = counts;
      }
    }
    for (int n = 0; n < kMaxNgramOrder; ++n) {
      const NgramCounts& c = evidence.counts;
      double h = c.histogram[n];
      double kp = c.keypoint[n];
      if (verified) {
        // Verified matches lying on complete keypoint n-grams, over the smaller keypoint count
        // (docs/matching.md): the same evidence the default similarity scores.
        const int smaller = std::max(1, std::min(c.reference_keypoints, c.query_keypoints));
        kp = static_cast<double>(c.keypoint_ngram_matches[n]) / smaller;
      } else if (config_.normalise_counts) {
        h = c.histogram_possible[n] > 0 ? h / c.histogram_possible[n] : 0.0;
        kp = c.keypoint_possible[n] > 0 ? kp / c.keypoint_possible[n] : 0.0;
      }
      histogram_counts[n][k] = h;
      keypoint_counts[n][k] = kp;
    }
  }
  result.histogram = interpolate(histogram_counts, config_.laplace_alpha);
  result.keypoint = interpolate(keypoint_counts, config_.laplace_alpha);
  result.probabilities.assign(k_places, 0.0);
  // Thesis: histogram model x keypoint model. Verified-match scoring weighs them geometrically by the
  // similarity's histogram weight (0.05 in the default preset: nearly the keypoint model alone).
  const double w = verified ? config_.similarity.histogram_weight : 0.5;
  for (std::size_t k = 0; k < k_places; ++k)
    result.probabilities[k] = verified ? std::pow(result.histogram.probabilities[k], 2.0 * w) *
                                             std::pow(result.keypoint.probabilities[k], 2.0 * (1.0 - w))
                                       : result.histogram.probabilities[k] * result.keypoint.probabilities[k];
  normalise(result.probabilities);
  const auto best = std::max_element(result.probabilities.begin(), result.probabilities.end());
  result.best_place = static_cast<int>(best - result.probabilities.begin());
  result.best_probability = *best;
  return result;
}

}  // namespace toposlam
