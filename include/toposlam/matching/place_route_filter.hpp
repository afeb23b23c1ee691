// Localisation along a route: the per-image place probabilities of PlaceLocalizer, filtered over a
// traversal. The places are in route order (the order the robot passes them: place k is followed by
// k + 1, the last by the first on a loop) and the queries arrive in time order, so the place of the
// previous query predicts the place of this one: a robot mostly stays in its place or moves on to the
// next. One forward step of a hidden Markov model (the same idea as the transition model of thesis
// chapter 5, applied to labelled places):
//
//     predicted(k) = sum_j belief(j) T(j, k)
//     T(j, k)      = (stay [k = j] + (1 - stay) [k = next(j)] + jump) / (1 + K jump)
//     belief'(k)   = predicted(k) p(k | image) / sum
//
// `jump` gives every place, the current one included, a small share, so a robot that was lost or carried
// elsewhere (or a place the route skips) is found again within a few images. The first image of a
// traversal has no prediction: its belief is the image's own probabilities.
//
// Measured on both bundled real sets (docs/matching.md, "Localisation along a route"); chosen there:
// stay 0.7, jump 0.01.
//
// On a map the route is a graph: setSuccessors() replaces "the next place" with each place's successors
// in the map (the topology's edges), the (1 - stay) share split over them by weight. A place without a
// successor keeps that share (the robot stays until the evidence says otherwise). The localisation-only
// mode runs it over the map's nodes, frame by frame (docs/daemon.md, "Localisation only").
// Plain class: no I/O, no clock, no randomness.
#pragma once

#include <span>
#include <string>
#include <vector>

namespace toposlam {

struct PlaceRouteFilterConfig {
  double stay_probability = 0.7;  ///< share of staying in the place; the rest moves to the next; [0, 1]
  double jump_weight = 0.01;      ///< weight of every place besides stay and next (before normalising); >= 0
  bool loop = true;               ///< the route is a loop: the last place is followed by the first
  std::string validate() const;   ///< empty when valid, else the first problem
};

class PlaceRouteFilter {
 public:
  /// places >= 1. Throws std::invalid_argument on an invalid config or no place.
  PlaceRouteFilter(const PlaceRouteFilterConfig& config, int places);

  /// Folds in the next image's place probabilities (one per place, in route order, >= 0; they need not
  /// sum to 1) and returns the filtered belief, which sums to 1. An image with no evidence at all (all 0
  /// or non-finite) leaves the prediction alone. Throws std::invalid_argument on a size mismatch.
  const std::vector<double>& update(std::span<const double> image_probabilities);

  /// One place's successors: (place, weight > 0), e.g. the map's edges with their traversal counts.
  struct Successor {
    int place = 0;
    double weight = 1.0;
  };
  /// Replaces the route by a graph: successors[j] are the places reached from place j (one list per
  /// place). Throws std::invalid_argument on a size mismatch, a place out of range or a weight that is
  /// not positive and finite.
  void setSuccessors(std::vector<std::vector<Successor>> successors);
  /// Changes the share of staying between two updates (e.g. calibrated from the stream's place lengths);
  /// throws std::invalid_argument outside [0, 1].
  void setStayProbability(double stay);

  /// Starts a new traversal: the next update has no prediction.
  void reset() { started_ = false; }

  const std::vector<double>& belief() const { return belief_; }
  int placeCount() const { return static_cast<int>(belief_.size()); }

 private:
  PlaceRouteFilterConfig config_;
  std::vector<double> belief_;
  std::vector<double> predicted_;  // scratch, reused
  std::vector<std::vector<Successor>> successors_;  // empty: the route (k -> k + 1)
  bool started_ = false;
};

}  // namespace toposlam
