// Localisation only, frame by frame, among a saved map's nodes: see node_localizer.hpp.
#include "toposlam/matching/node_localizer.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <utility>


namespace toposlam {

namespace {

/// The shortest place the share of staying is calibrated from (1 - 1/2: a place of one frame would say
/// "never stay").
constexpr double kMinPlaceFrames = 2.0;

PlaceRouteFilterConfig graphConfig(const NodeLocalizerConfig& config) {
  PlaceRouteFilterConfig c;
  c.stay_probability = 0.5;  // replaced by the calibration before the second frame
  c.jump_weight = config.jump_weight;
  c.loop = false;            // successors come from the map's edges
  return c;
}

/// The localiser's places: the nodes' representatives (moved out of `nodes`, which keeps ids and edges).
std::vector<LabelledPlace> takeReferences(MapNodes& nodes) {
  std::vector<LabelledPlace> places = std::move(nodes.nodes);
  nodes.nodes.clear();
  return places;
}

}  // namespace

std::string NodeLocalizerConfig::validate() const {
  if (std::string problem = localizer.validate(); !problem.empty()) return problem;
  if (!(min_probability >= 0.0 && min_probability <= 1.0)) return "min_probability: must be in [0, 1]";
  if (!(jump_weight >= 0.0 && std::isfinite(jump_weight))) return "jump_weight: must be >= 0";
  return "";
}

NodeLocalizer::NodeLocalizer(const NodeLocalizerConfig& config, MapNodes nodes)
    : config_(config),
      nodes_(std::move(nodes)),
      localizer_(config.localizer, takeReferences(nodes_)),
      graph_(graphConfig(config), static_cast<int>(nodes_.node_ids.size())) {
  if (std::string problem = config_.validate(); !problem.empty())
    throw std::invalid_argument("localisation config: " + problem);
  graph_.setSuccessors(nodes_.successors);
}

void NodeLocalizer::calibrate() {
  const double length = places_closed_ > 0 ? static_cast<double>(place_frames_) / static_cast<double>(places_closed_)
                                           : static_cast<double>(frames_seen_);
  stay_ = 1.0 - 1.0 / std::max(kMinPlaceFrames, length);
  graph_.setStayProbability(stay_);
}

void NodeLocalizer::placeClosed(std::int64_t frames) {
  if (frames <= 0) return;
  place_frames_ += frames;
  ++places_closed_;
}

NodeFix NodeLocalizer::update(const Fingerprint& frame, int alternatives) {
  ++frames_seen_;
  calibrate();
  const Localization l = localizer_.localize(frame);
  return answer(graph_.update(l.probabilities), alternatives);
}

NodeFix NodeLocalizer::localizeOnce(const Fingerprint& fingerprint) const {
  return answer(localizer_.localize(fingerprint).probabilities, 0);
}

NodeFix NodeLocalizer::answer(const std::vector<double>& belief, int alternatives) const {
  NodeFix fix;
  if (belief.empty()) return fix;
  std::vector<std::size_t> order(belief.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto shown = std::min(order.size(), static_cast<std::size_t>(std::max(0, alternatives)) + 1);
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(shown), order.end(),
                    [&](std::size_t a, std::size_t b) { return belief[a] > belief[b] || (belief[a] == belief[b] && a < b); });
  fix.best_node = nodes_.node_ids[order[0]];
  fix.probability = belief[order[0]];
  fix.node = fix.probability >= config_.min_probability ? fix.best_node : -1;
  for (std::size_t i = 1; i < shown; ++i) fix.alternatives.push_back({nodes_.node_ids[order[i]], belief[order[i]]});
  return fix;
}

}  // namespace toposlam
