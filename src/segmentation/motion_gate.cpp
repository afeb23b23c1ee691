// MotionGate; see the header.
#include "toposlam/segmentation/motion_gate.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace toposlam {

std::string MotionGateConfig::validate() const {
  std::ostringstream message;
  if (!(standing_speed_mps >= 0.0 && standing_speed_mps <= 10.0)) {
    message << "standing_speed_mps: " << standing_speed_mps << " m/s is outside the allowed range [0, 10]";
  } else if (!(standing_turn_rate_rps >= 0.0 && standing_turn_rate_rps <= 100.0)) {
    message << "standing_turn_rate_rps: " << standing_turn_rate_rps << " rad/s is outside the allowed range [0, 100]";
  } else if (!(standing_after_s >= 0.0 && standing_after_s <= 3600.0)) {
    message << "standing_after_s: " << standing_after_s << " s is outside the allowed range [0, 3600]";
  } else if (!(timeout_s > 0.0 && timeout_s <= 3600.0)) {
    message << "timeout_s: " << timeout_s << " s is outside the allowed range (0, 3600]";
  } else if (!(clock_tolerance_s > 0.0 && clock_tolerance_s <= 3600.0)) {
    message << "clock_tolerance_s: " << clock_tolerance_s << " s is outside the allowed range (0, 3600]";
  } else if (!(max_speed_mps > 0.0 && max_speed_mps <= 1000.0)) {
    message << "max_speed_mps: " << max_speed_mps << " m/s is outside the allowed range (0, 1000]";
  } else if (!(max_turn_rate_rps > 0.0 && max_turn_rate_rps <= 1000.0)) {
    message << "max_turn_rate_rps: " << max_turn_rate_rps << " rad/s is outside the allowed range (0, 1000]";
  }
  return message.str();
}

MotionGate::MotionGate(const MotionGateConfig& config) : config_(config) {
  if (const std::string problem = config_.validate(); !problem.empty()) {
    throw std::invalid_argument("motion gate config: " + problem);
  }
}

std::int64_t* MotionGate::refusal(double time_s, double distance_increment_m, double speed_mps, double turn_rate_rps,
                                  double received_s) {
  if (!std::isfinite(time_s) || !std::isfinite(distance_increment_m) || !std::isfinite(speed_mps) ||
      !std::isfinite(turn_rate_rps))
    return &refusals_.not_finite;
  // NaN received_s: no receiver clock to check against (an infinite one is no clock either).
  if (std::isfinite(received_s) && std::abs(time_s - received_s) > config_.clock_tolerance_s)
    return &refusals_.off_clock;
  // The longest the increment may have taken: since the last accepted sample, at least timeout_s (the
  // first sample, or samples stamped close together, may carry a link's lost frames).
  const double interval_s = samples_ > 0 ? std::max(time_s - last_time_s_, config_.timeout_s) : config_.timeout_s;
  if (std::abs(speed_mps) > config_.max_speed_mps || std::abs(turn_rate_rps) > config_.max_turn_rate_rps ||
      std::abs(distance_increment_m) > config_.max_speed_mps * interval_s)
    return &refusals_.implausible;
  if (samples_ > 0 && time_s < last_time_s_) return &refusals_.earlier;
  return nullptr;
}

bool MotionGate::addSample(double time_s, double distance_increment_m, double speed_mps, double turn_rate_rps,
                           double received_s) {
  if (std::int64_t* reason = refusal(time_s, distance_increment_m, speed_mps, turn_rate_rps, received_s)) {
    ++*reason;
    ++refused_since_accepted_;
    return false;
  }
  refused_since_accepted_ = 0;
  const bool gap = samples_ > 0 && time_s - last_time_s_ > config_.timeout_s;
  const bool slow =
      std::abs(speed_mps) < config_.standing_speed_mps && std::abs(turn_rate_rps) < config_.standing_turn_rate_rps;
  if (slow && (!slow_ || gap || samples_ == 0)) slow_since_s_ = time_s;
  slow_ = slow;
  distance_m_ += std::abs(distance_increment_m);
  if (samples_ > 0 && !gap) turned_rad_ += std::abs(turn_rate_rps) * (time_s - last_time_s_);
  last_time_s_ = time_s;
  ++samples_;
  return true;
}

MotionState MotionGate::at(double time_s) const {
  MotionState state;
  if (samples_ == 0 || !std::isfinite(time_s) || time_s - last_time_s_ > config_.timeout_s) return state;
  state.known = true;
  state.distance_m = distance_m_;
  state.turned_rad = turned_rad_;
  state.standing = slow_ && time_s - slow_since_s_ >= config_.standing_after_s;
  return state;
}

}  // namespace toposlam
