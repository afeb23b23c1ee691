// Localisation only (docs/daemon.md, "Localisation only"): where the robot is, frame by frame, among the
// nodes of a saved map that is never changed. The thesis' chapter 3 localisation (PlaceLocalizer: naive
// Bayes over the n-gram counts of each node's representatives) gives every frame a distribution over the
// nodes; a hidden Markov model over the map's graph (PlaceRouteFilter with the topology's edges as
// successors) carries the belief from frame to frame, so one misleading frame does not move the robot.
//
//   - The nodes, their representatives and their edges are those of the map's most probable topology
//     (mapNodesOf in algorithm_stages.hpp builds them from a loaded map).
//   - The share of staying in a node between two frames is calibrated from the stream: 1 - 1 / L, where L
//     is the mean length in frames of the places the segmentation closed so far in this run (before the
//     first one, the frames seen so far), floored at 2 frames. No rate is assumed.
//   - A frame whose best node has a belief under min_probability answers "not a known node" (node -1), as
//     when the robot drives where the map has never been.
//
// Plain class: no threads, I/O, clock or randomness; deterministic.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "toposlam/matching/place_localizer.hpp"
#include "toposlam/matching/place_route_filter.hpp"

namespace toposlam {

struct NodeLocalizerConfig {
  PlaceLocalizerConfig localizer;  ///< similarity.* of the config (the map's similarity)
  double min_probability = 0.5;    ///< map.localize.min_probability; [0, 1]
  double jump_weight = 0.01;       ///< map.localize.jump_weight; >= 0 (relocalisation anywhere)
  std::string validate() const;
};

/// The nodes of a map's most probable topology, as the localiser needs them.
struct MapNodes {
  std::vector<int> node_ids;                  ///< per localised node: its id in the topology
  std::vector<LabelledPlace> nodes;           ///< per localised node: its representatives (label = id)
  std::vector<std::vector<PlaceRouteFilter::Successor>> successors;  ///< edges, weight = traversals
};

/// One frame's answer.
struct NodeFix {
  int node = -1;                 ///< topology node id; -1: not a known node (belief under min_probability)
  double probability = 0.0;      ///< the belief of the best node (also when it is under the threshold)
  int best_node = -1;            ///< the best node whatever its belief
  struct Alternative {
    int node = -1;
    double probability = 0.0;
  };
  std::vector<Alternative> alternatives;  ///< the next best nodes, best first
};

class NodeLocalizer {
 public:
  /// Throws std::invalid_argument on an invalid config or a map without nodes.
  NodeLocalizer(const NodeLocalizerConfig& config, MapNodes nodes);

  /// Folds in the next frame of the stream and answers for it (`alternatives`: how many runners-up).
  NodeFix update(const Fingerprint& frame, int alternatives = 0);
  /// A place of `frames` frames closed in this run (calibrates the share of staying).
  void placeClosed(std::int64_t frames);
  /// Where one fingerprint alone (no history) would put the robot, e.g. a closed place's representative.
  NodeFix localizeOnce(const Fingerprint& fingerprint) const;

  double stayProbability() const { return stay_; }
  int nodeCount() const { return static_cast<int>(nodes_.node_ids.size()); }
  const MapNodes& nodes() const { return nodes_; }

 private:
  NodeFix answer(const std::vector<double>& belief, int alternatives) const;
  void calibrate();

  NodeLocalizerConfig config_;
  MapNodes nodes_;
  PlaceLocalizer localizer_;
  PlaceRouteFilter graph_;
  std::int64_t frames_seen_ = 0;
  std::int64_t place_frames_ = 0;
  std::int64_t places_closed_ = 0;
  double stay_ = 0.5;
};

}  // namespace toposlam
