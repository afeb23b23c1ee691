// Algorithm 4.1 of the thesis, line by line, with one correction: when a peak is found the pseudo-code
// resets minValue to the current value but not minIdx, so a valley whose minimum is that very value
// would report a stale frame. Billauer's original (and this code) sets both.
#include "toposlam/segmentation/valley_detector.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace toposlam {

std::string ValleyDetectorConfig::validate(double lambda2_max) const {
  std::ostringstream problem;
  if (!std::isfinite(gamma) || gamma < 0.0 || gamma > lambda2_max) {
    problem << "gamma: " << gamma << " is outside the allowed range [0, " << lambda2_max
            << "] (the largest Fiedler value for the window)";
  } else if (!std::isfinite(delta) || delta < 0.0 || delta > gamma) {
    problem << "delta: " << delta << " is outside the allowed range [0, gamma = " << gamma << "]";
  }
  return problem.str();
}

ValleyDetector::ValleyDetector(const ValleyDetectorConfig& config) : config_(config) {
  if (const std::string problem = config_.validate(); !problem.empty()) {
    throw std::invalid_argument("valley detector config: " + problem);
  }
}

void ValleyDetector::reset() {
  look_for_maximum_ = true;
  max_value_ = -std::numeric_limits<double>::infinity();
  min_value_ = std::numeric_limits<double>::infinity();
  min_index_ = -1;
}

std::optional<std::int64_t> ValleyDetector::update(std::int64_t frame_index, double value) {
  if (!std::isfinite(value)) return std::nullopt;
  std::optional<std::int64_t> valley;

  // Is the current value an extremum? (else-if as in the thesis: a new maximum is never a new minimum)
  if (value > max_value_) {
    max_value_ = value;
  } else if (value < min_value_) {
    min_value_ = value;
    min_index_ = frame_index;
  }

  if (look_for_maximum_) {
    if (value < max_value_ - config_.delta && max_value_ >= config_.gamma) {  // peak found
      look_for_maximum_ = false;
      min_value_ = value;
      min_index_ = frame_index;
    }
  } else if (value > min_value_ + config_.delta) {  // valley found
    look_for_maximum_ = true;
    max_value_ = value;
    valley = min_index_;
  }
  return valley;
}

}  // namespace toposlam
