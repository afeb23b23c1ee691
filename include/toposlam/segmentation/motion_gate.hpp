// The robot's own motion for segmentation (thesis sections 4.4 and 6.3; docs/segmentation.md,
// "Motion-aware segmentation"). Fed with motion samples (time, distance travelled since the previous
// sample, speed, turn rate), e.g. decoded from TOPOSLAM_MOTION, it answers per frame time:
//   known     a sample arrived within `timeout_s` of the frame (the link is alive);
//   standing  known, and every sample for at least `standing_after_s` up to now had a speed below
//             `standing_speed_mps` and a turn rate below `standing_turn_rate_rps` (a short halt is not a
//             stop, and a robot turning on the spot is not standing: its view sweeps the room);
//   distance  the distance travelled so far (sum of |increment|; reversing counts as travel).
// The FiedlerSegmenter then leaves standing frames out of its window and, with segmentation.window_m > 0,
// sizes the window in metres (FiedlerSegmenter::addFrame with a MotionState).
//
// Plain algorithm code: no clock, no threads; times are whatever clock the caller uses for both the
// samples and the frames (seconds). A gap in the samples longer than `timeout_s` restarts the standing run.
// Not thread-safe: one instance per stream, fed by its one thread. Does not allocate.
//
// A sample that cannot be right is refused, counted by reason (MotionRefusals) and never becomes the
// reference the next samples are compared with, so one bad message cannot turn motion off:
//   not finite   a time or value that is NaN or infinite;
//   off clock    the caller gives the receiver's time (same clock) and the sample's own time differs from
//                it by more than `clock_tolerance_s` (a sender stamping with another clock, a replayed
//                or forged message);
//   implausible  speed above `max_speed_mps`, yaw rate above `max_turn_rate_rps`, or a distance increment
//                above max_speed_mps x max(time since the last accepted sample, timeout_s);
//   earlier      older than the newest accepted sample (after a sample within the tolerance but ahead
//                of the others, at most clock_tolerance_s of samples are refused this way).
#pragma once

#include <cstdint>
#include <limits>
#include <string>

namespace toposlam {

struct MotionGateConfig {
  /// Slower than this (absolute speed, m/s) counts as standing; allowed [0, 10].
  double standing_speed_mps = 0.05;
  /// Turning faster than this (absolute yaw rate, rad/s) is moving, whatever the speed; allowed [0, 100].
  /// (Measured on the simulated office: without it the turns on the spot at each corner count as stops.)
  double standing_turn_rate_rps = 0.1;
  /// The robot stands once it has been slower than standing_speed_mps for this long, seconds; [0, 3600].
  double standing_after_s = 1.0;
  /// Motion is known while the newest sample is at most this old at the frame's time, seconds; (0, 3600].
  double timeout_s = 1.0;
  /// A sample whose time differs from the receiver's clock by more than this is refused, seconds; (0, 3600].
  double clock_tolerance_s = 1.0;
  /// Faster than this (absolute speed, m/s) cannot be the robot: the sample is refused; (0, 1000].
  double max_speed_mps = 5.0;
  /// Turning faster than this (absolute yaw rate, rad/s) cannot be the robot: refused; (0, 1000].
  double max_turn_rate_rps = 10.0;
  /// Returns "" when valid, else "<key>: <problem, allowed range>".
  std::string validate() const;
};

/// What the gate says about one frame time.
struct MotionState {
  bool known = false;  ///< a sample within timeout_s (link alive); false: segment by time as without motion
  bool standing = false;    ///< known, slower than standing_speed_mps and not turning, for standing_after_s or more
  double distance_m = 0.0;  ///< travelled since the first sample (meaningful only when known)
  double turned_rad = 0.0;  ///< |yaw| turned since the first sample, integrated from the yaw rate
};

/// Samples refused, by reason (see the file comment).
struct MotionRefusals {
  std::int64_t not_finite = 0;
  std::int64_t off_clock = 0;
  std::int64_t implausible = 0;
  std::int64_t earlier = 0;
  std::int64_t total() const { return not_finite + off_clock + implausible + earlier; }
};

class MotionGate {
 public:
  /// Throws std::invalid_argument on an invalid config.
  explicit MotionGate(const MotionGateConfig& config);

  /// One motion sample: `distance_increment_m` travelled since the previous sample, current `speed_mps`
  /// and yaw rate `turn_rate_rps` (0 when the source has none); `received_s`, the receiver's clock when the
  /// sample arrived (NaN: no receiver clock, e.g. a recorded file, and no clock check). Returns false (and
  /// counts it in refusals()) when the sample is refused (see the file comment).
  bool addSample(double time_s, double distance_increment_m, double speed_mps, double turn_rate_rps = 0.0,
                 double received_s = std::numeric_limits<double>::quiet_NaN());

  /// The state at a frame taken at `time_s` (from the samples added so far).
  MotionState at(double time_s) const;

  const MotionGateConfig& config() const { return config_; }
  std::int64_t samples() const { return samples_; }
  std::int64_t rejectedSamples() const { return refusals_.total(); }
  const MotionRefusals& refusals() const { return refusals_; }
  /// Samples refused since the newest accepted one (0 when the last sample was accepted).
  std::int64_t refusedSinceAccepted() const { return refused_since_accepted_; }
  double distanceM() const { return distance_m_; }

 private:
  MotionGateConfig config_;
  std::int64_t samples_ = 0;
  /// Which rule refuses the sample, or nullptr when it is accepted.
  std::int64_t* refusal(double time_s, double distance_increment_m, double speed_mps, double turn_rate_rps,
                        double received_s);

  MotionRefusals refusals_;
  std::int64_t refused_since_accepted_ = 0;
  double last_time_s_ = 0.0;
  double distance_m_ = 0.0;
  double turned_rad_ = 0.0;
  bool slow_ = false;          ///< the newest sample was below standing_speed_mps and not turning
  double slow_since_s_ = 0.0;  ///< time of the first sample of the current slow run
};

}  // namespace toposlam
