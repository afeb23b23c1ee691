// From controller messages to robot motion: increments since the previous sample in the robot frame
// (x forward, y left, z up; turn counter-clockwise positive), current speeds, and whether the robot is
// moving, stamped on the host's monotonic clock. This is what the bridge publishes as motion_t.
//
// Sources, in order of preference (a link uses one):
//   wheel link WHEEL_ODOMETRY  cumulative wheel travel: a lost frame loses no distance.
//   wheel link BODY_VELOCITY   integrated (trapezoid) between samples; a gap longer than max_gap_s is
//                              not integrated (counted), since nothing is known about it.
//   MAVLink ODOMETRY           local position + attitude quaternion, velocity in the child frame.
//   MAVLink LOCAL_POSITION_NED + the latest ATTITUDE (used only while no ODOMETRY arrives).
// A controller restart (its clock steps back, a new boot id, an ODOMETRY reset_counter change) starts
// again from the next message: no increment spans a restart.
//
// Controller time -> host time: offset = the smallest (host receive time - controller time) seen, the
// estimate least inflated by transport delay; re-estimated after a restart, and when the mapped time falls
// behind the host's receive time by more than clock_tolerance_s (the controller's clock runs slow), so a
// published time is never later than its receive time nor more than the tolerance before it.
// Plain class: no clocks of its own (the host time is passed in), no I/O; one thread.
//
// Messages that cannot be right are refused and counted, and never become the reference:
//   off clock    the controller's clock ran ahead of the host's by more than clock_tolerance_s since the
//                last accepted message (e.g. a time of 2^62 us), or beyond 2^63 - 1 us. If that goes on
//                for longer than the tolerance of host time, the controller's clock did jump: it counts as
//                a restart and the message becomes the new reference.
//   implausible  a sample faster than max_speed_mps or turning faster than max_turn_rate_rps, or whose
//                increment is longer than those speeds allow over max(interval, max_gap_s). The next
//                message becomes the reference: no increment spans the refused one.
// All time arithmetic is on 64-bit integers checked for overflow.
#pragma once

#include <cstdint>
#include <optional>

#include "toposlam/firmware/mavlink.hpp"
#include "toposlam/firmware/wheel_link.hpp"

namespace toposlam::firmware {

struct MotionSample {
  std::int64_t utime = 0;         ///< host CLOCK_MONOTONIC of the measurement, microseconds
  double forward_m = 0;           ///< since the previous sample
  double lateral_m = 0;           ///< to the left
  double turn_rad = 0;            ///< counter-clockwise
  double linear_velocity_mps = 0;
  double angular_velocity_rps = 0;
  bool moving = false;
};

struct MotionEstimatorConfig {
  double moving_speed_mps = 0.02;   ///< faster than this counts as moving, m/s
  double moving_turn_rps = 0.05;    ///< turning faster than this counts as moving, rad/s
  double max_gap_s = 0.5;           ///< velocity samples further apart are not integrated, s
  double max_speed_mps = 5.0;       ///< faster cannot be the robot: the sample is refused, m/s
  double max_turn_rate_rps = 10.0;  ///< turning faster cannot be the robot: refused, rad/s
  double clock_tolerance_s = 1.0;   ///< how far the controller's clock may run ahead of (or the mapped time
                                    ///< fall behind) the host's, s
};

struct MotionCounters {
  std::uint64_t samples = 0;    ///< MotionSamples produced
  std::uint64_t restarts = 0;   ///< controller restarts / estimator resets seen
  std::uint64_t gaps = 0;       ///< velocity gaps not integrated
  std::uint64_t invalid = 0;    ///< messages with NaN, zero track width or an unsupported frame
  std::uint64_t off_clock = 0;  ///< messages refused: the controller's time ran ahead of the host's
  std::uint64_t implausible = 0;  ///< samples refused: faster or turning faster than the limits
  std::uint64_t clock_resyncs = 0;  ///< offset re-estimated: the mapped time fell behind the host's
  std::uint64_t heartbeats = 0;
  std::uint64_t statuses = 0;
};

class MotionEstimator {
 public:
  explicit MotionEstimator(MotionEstimatorConfig config = {}) : config_(config) {}

  std::optional<MotionSample> onWheel(const wheel::Message& message, std::int64_t host_us);
  std::optional<MotionSample> onMavlink(const mavlink::Message& message, std::int64_t host_us);

  const MotionCounters& counters() const { return counters_; }
  /// The latest wheel-link status (faults, battery), if any arrived.
  const std::optional<twl_status_t>& lastStatus() const { return status_; }

 private:
  std::optional<MotionSample> wheelOdometry(const twl_wheel_odometry_t& m, std::int64_t host_us);
  std::optional<MotionSample> bodyVelocity(const twl_body_velocity_t& m, std::int64_t host_us);
  std::optional<MotionSample> odometry(const mavlink::Odometry& m, std::int64_t host_us);
  std::optional<MotionSample> localPosition(const mavlink::LocalPositionNed& m, std::int64_t host_us);
  /// Position (north, east) and yaw (NED, clockwise) -> increment in the robot frame.
  std::optional<MotionSample> fromPose(std::uint64_t controller_us, double north, double east, double yaw,
                                       double forward_speed, double yaw_rate_ned, std::int64_t host_us);
  /// Host time of a controller time; nullopt (counted) when the controller time is refused.
  std::optional<std::int64_t> controllerTime(std::uint64_t controller_us, std::int64_t host_us);
  /// `s` (spanning `dt_s` of controller time) within the limits; else counted, and the next message
  /// becomes the reference.
  std::optional<MotionSample> plausible(const MotionSample& s, double dt_s);
  void restart();
  bool isMoving(double v, double w) const;

  MotionEstimatorConfig config_;
  MotionCounters counters_;
  // Clock mapping.
  bool have_time_ = false;
  std::uint64_t last_controller_us_ = 0;
  std::int64_t last_host_us_ = 0;         ///< host time of the last accepted message
  std::int64_t offset_us_ = 0;
  std::optional<std::int64_t> refused_since_us_;  ///< host time of the first of the current off-clock run
  // Previous sample of the active source.
  bool have_previous_ = false;
  std::int32_t prev_left_um_ = 0, prev_right_um_ = 0;
  double prev_vx_ = 0, prev_vy_ = 0, prev_wz_ = 0;
  double prev_north_ = 0, prev_east_ = 0, prev_yaw_ = 0;
  std::uint64_t prev_controller_us_ = 0;
  // Boot identity.
  std::optional<std::uint16_t> boot_id_;
  std::optional<std::uint8_t> reset_counter_;
  // MAVLink helpers.
  std::optional<mavlink::Attitude> attitude_;
  bool odometry_seen_ = false;
  std::optional<twl_status_t> status_;
};

}  // namespace toposlam::firmware
