// The topology filter's models as plain functions: the transition model (the gamma pdf over "stay" and
// the successors, eq. 5.8's prior), the appearance likelihoods (relative likelihood, normalised entropy,
// eq. 5.7's new node) and the validation of the filter's config. See topology_particle_filter.hpp.
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "node_likelihoods.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

using topology_detail::entropyFromSums;
using topology_detail::idx;
using topology_detail::lLogL;

std::string TopologyFilterConfig::validate() const {
  if (particles < 1 || particles > 1000000) return "particles: must be in [1, 1000000]";
  if (!(alpha > 0.0 && alpha <= 1e6)) return "alpha: must be in (0, 1e6]";
  if (!(new_node_probability > 0.0 && new_node_probability < 1.0))
    return "new_node_probability: must be in (0, 1)";
  if (!(gamma_shape > 0.0 && gamma_shape <= 1000.0)) return "gamma_shape: must be in (0, 1000]";
  if (!(gamma_scale > 0.0 && gamma_scale <= 100.0)) return "gamma_scale: must be in (0, 100]";
  if (max_successors < 1 || max_successors > kTopologyMaxSuccessors)
    return "max_successors: must be in [1, 8]";
  if (max_representatives_per_node < 1 || max_representatives_per_node > kTopologyMaxRepresentatives) {
    return "max_representatives_per_node: must be in [1, 16]";
  }
  if (likelihood != LikelihoodModel::Absolute && likelihood != LikelihoodModel::Relative)
    return "likelihood: must be absolute or relative";
  if (!(relative_slope > 0.0 && relative_slope <= 100.0)) return "relative_slope: must be in (0, 100]";
  if (!(relative_offset >= -10.0 && relative_offset <= 10.0)) return "relative_offset: must be in [-10, 10]";
  if (!(relative_sigma_floor > 0.0 && relative_sigma_floor <= 1.0))
    return "relative_sigma_floor: must be in (0, 1]";
  if (!(new_node_likelihood_floor >= 0.0 && new_node_likelihood_floor < 1.0))
    return "new_node_likelihood_floor: must be in [0, 1)";
  if (const std::string problem = candidates.validate(); !problem.empty()) return "candidates." + problem;
  return "";
}

std::string CandidateSelectionConfig::validate() const {
  if (exhaustive_up_to < 0 || exhaustive_up_to > 1000000000) return "exhaustive_up_to: must be in [0, 1000000000]";
  if (candidates < 1 || candidates > 100000) return "candidates: must be in [1, 100000]";
  if (background_samples < 0 || background_samples > 100000) return "background_samples: must be in [0, 100000]";
  if (const std::string problem = index.validate(); !problem.empty()) return "index." + problem;
  return "";
}

const char* toString(LikelihoodModel model) {
  return model == LikelihoodModel::Relative ? "relative" : "absolute";
}

LikelihoodModel parseLikelihoodModel(const std::string& name) {
  if (name == "absolute") return LikelihoodModel::Absolute;
  if (name == "relative") return LikelihoodModel::Relative;
  throw std::invalid_argument("likelihood model '" + name + "': expected absolute or relative");
}

double relativeLikelihood(double similarity, double others_sum, double others_sum_sq, int others_count,
                          double slope, double offset, double sigma_floor) {
  double z = 0.0;
  if (others_count > 0) {
    const double n = static_cast<double>(others_count);
    const double mean = others_sum / n;
    const double variance = std::max(0.0, others_sum_sq / n - mean * mean);
    z = (similarity - mean) / std::max(std::sqrt(variance), sigma_floor);
  }
  return 1.0 / (1.0 + std::exp(-slope * (z - offset)));
}

double gammaPdf(double x, double shape, double scale) {
  if (!(x > 0.0)) return 0.0;
  return std::exp((shape - 1.0) * std::log(x) - x / scale - std::lgamma(shape) - shape * std::log(scale));
}

double normalisedEntropy(std::span<const double> likelihoods) {
  double sum = 0.0, sum_l_log_l = 0.0;
  for (double l : likelihoods) {
    sum += l;
    sum_l_log_l += lLogL(l);
  }
  return entropyFromSums(sum, sum_l_log_l, static_cast<int>(likelihoods.size()));
}

double newNodeLikelihood(std::span<const double> known_likelihoods) {
  if (known_likelihoods.empty()) return 1.0;
  const double max = *std::max_element(known_likelihoods.begin(), known_likelihoods.end());
  return normalisedEntropy(known_likelihoods) * (1.0 - max);
}

KnownNodeTransition knownNodeTransition(const TopologyFilterConfig& config) {
  KnownNodeTransition t;
  std::array<double, kTopologyMaxSuccessors + 1> raw{};
  double total = 0.0;
  for (int j = 0; j <= config.max_successors; ++j) {
    raw[idx(j)] = gammaPdf(j + 1.0, config.gamma_shape, config.gamma_scale);
    total += raw[idx(j)];
  }
  const double scale = (1.0 - config.new_node_probability) / total;
  t.stay = raw[0] * scale;
  for (int j = 1; j <= config.max_successors; ++j) t.successor.push_back(raw[idx(j)] * scale);
  t.new_node = config.new_node_probability;
  return t;
}

}  // namespace toposlam
