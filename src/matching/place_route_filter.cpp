// Localisation along a route: see place_route_filter.hpp.
#include "toposlam/matching/place_route_filter.hpp"

#include <cmath>
#include <numeric>
#include <stdexcept>
#include <utility>

namespace toposlam {

std::string PlaceRouteFilterConfig::validate() const {
  if (!(stay_probability >= 0.0 && stay_probability <= 1.0))
    return "stay_probability: must be in [0, 1] (share of staying in the place between two images)";
  if (!(jump_weight >= 0.0 && std::isfinite(jump_weight)))
    return "jump_weight: must be >= 0 (weight of moving to any place off the route)";
  return "";
}

PlaceRouteFilter::PlaceRouteFilter(const PlaceRouteFilterConfig& config, int places) : config_(config) {
  if (std::string problem = config_.validate(); !problem.empty())
    throw std::invalid_argument("route filter config: " + problem);
  if (places < 1) throw std::invalid_argument("route filter: needs at least one place");
  belief_.assign(static_cast<std::size_t>(places), 1.0 / places);
  predicted_.assign(static_cast<std::size_t>(places), 0.0);
}

void PlaceRouteFilter::setSuccessors(std::vector<std::vector<Successor>> successors) {
  if (successors.size() != belief_.size())
    throw std::invalid_argument("route filter: successors of " + std::to_string(successors.size()) + " places for " +
                                std::to_string(belief_.size()));
  for (const auto& out : successors)
    for (const Successor& s : out) {
      if (s.place < 0 || static_cast<std::size_t>(s.place) >= belief_.size())
        throw std::invalid_argument("route filter: successor " + std::to_string(s.place) + " is not a place");
      if (!(s.weight > 0.0 && std::isfinite(s.weight)))
        throw std::invalid_argument("route filter: a successor's weight must be positive and finite");
    }
  successors_ = std::move(successors);
}

void PlaceRouteFilter::setStayProbability(double stay) {
  PlaceRouteFilterConfig next = config_;
  next.stay_probability = stay;
  if (std::string problem = next.validate(); !problem.empty())
    throw std::invalid_argument("route filter config: " + problem);
  config_ = next;
}

const std::vector<double>& PlaceRouteFilter::update(std::span<const double> image_probabilities) {
  const std::size_t k_places = belief_.size();
  if (image_probabilities.size() != k_places)
    throw std::invalid_argument("route filter: " + std::to_string(image_probabilities.size()) +
                                " image probabilities for " + std::to_string(k_places) + " places");
  if (started_) {
    const double jump = config_.jump_weight;
    const double row_sum = 1.0 + static_cast<double>(k_places) * jump;
    const double belief_sum = std::accumulate(belief_.begin(), belief_.end(), 0.0);
    for (std::size_t k = 0; k < k_places; ++k) predicted_[k] = jump * belief_sum;
    for (std::size_t j = 0; j < k_places; ++j) {
      predicted_[j] += config_.stay_probability * belief_[j];
      const double moving = (1.0 - config_.stay_probability) * belief_[j];
      if (successors_.empty()) {
        const std::size_t next = j + 1 < k_places ? j + 1 : (config_.loop ? 0 : j);
        predicted_[next] += moving;
        continue;
      }
      const std::vector<Successor>& out = successors_[j];
      double total = 0.0;
      for (const Successor& s : out) total += s.weight;
      if (out.empty()) predicted_[j] += moving;
      for (const Successor& s : out) predicted_[static_cast<std::size_t>(s.place)] += moving * s.weight / total;
    }
    for (double& p : predicted_) p /= row_sum;
  } else {
    predicted_.assign(k_places, 1.0 / static_cast<double>(k_places));
  }
  double sum = 0.0;
  for (std::size_t k = 0; k < k_places; ++k) {
    const double evidence = image_probabilities[k];
    belief_[k] = predicted_[k] * (std::isfinite(evidence) && evidence > 0.0 ? evidence : 0.0);
    sum += belief_[k];
  }
  if (sum > 0.0 && std::isfinite(sum)) {
    for (double& b : belief_) b /= sum;
  } else {
    belief_ = predicted_;  // no usable evidence: the prediction alone
  }
  started_ = true;
  return belief_;
}

}  // namespace toposlam
