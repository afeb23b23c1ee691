// Online peak/valley detection on the Fiedler-value series (thesis Algorithm 4.1, adapted from Eli
// Billauer's peakdet). A peak is declared once the series has fallen `delta` below a maximum that is at
// least `gamma`; after a peak, a valley is declared once the series has risen `delta` above the
// minimum seen since, and the frame of that minimum is returned. Peaks lower than gamma are ignored
// (weakly connected stretches are not places); swings smaller than delta are noise.
//
// Deterministic and independent of time: the output depends only on the sequence of (frame, value)
// pairs fed in. Not thread-safe (one instance per stream).
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>

namespace toposlam {

struct ValleyDetectorConfig {
  /// Minimum height of a peak, on the lambda2 scale (thesis: 0.5; allowed [0, lambda2_max]).
  double gamma = 0.5;
  /// Minimum rise/fall between consecutive peaks and valleys (thesis: 0.25; allowed [0, gamma]).
  double delta = 0.25;
  /// Returns "" when valid, else "<key>: <problem, allowed range>". `lambda2_max` is n/(n-1) for the
  /// window the detector will see (the largest Fiedler value of L_sym for n nodes).
  std::string validate(double lambda2_max = 2.0) const;
};

class ValleyDetector {
 public:
  /// Throws std::invalid_argument naming the bad key when the config is invalid.
  explicit ValleyDetector(const ValleyDetectorConfig& config = {});

  /// Feeds the Fiedler value computed after frame `frame_index` (Algorithm 4.1's "currentValue").
  /// Returns the frame index of the valley when one is confirmed by this value, else std::nullopt.
  /// A non-finite value is ignored (returns std::nullopt and changes nothing).
  std::optional<std::int64_t> update(std::int64_t frame_index, double value);

  /// Back to the initial state (looking for a peak, no extrema seen).
  void reset();

  bool lookingForPeak() const { return look_for_maximum_; }
  double maxValue() const { return max_value_; }
  double minValue() const { return min_value_; }
  /// Frame of the lowest value since the last peak (the valley candidate); -1 before any.
  std::int64_t minIndex() const { return min_index_; }
  const ValleyDetectorConfig& config() const { return config_; }

 private:
  ValleyDetectorConfig config_;
  bool look_for_maximum_ = true;
  double max_value_ = -std::numeric_limits<double>::infinity();
  double min_value_ = std::numeric_limits<double>::infinity();
  std::int64_t min_index_ = -1;
};

}  // namespace toposlam
