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
// estimate least inflated by transport delay; re-estimated after a restart. Plain class: no clocks of
// its own (the host time is passed in), no I/O; one thread.
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
};

struct MotionCounters {
  std::uint64_t samples = 0;    ///< MotionSamples produced
  std::uint64_t restarts = 0;   ///< controller restarts / estimator resets seen
  std::uint64_t gaps = 0;       ///< velocity gaps not integrated
  std::uint64_t invalid = 0;    ///< messages with NaN, zero track width or an unsupported frame
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
  std::int64_t controllerTime(std::uint64_t controller_us, std::int64_t host_us);
  void restart();
  bool isMoving(double v, double w) const;

  MotionEstimatorConfig config_;
  MotionCounters counters_;
  // Clock mapping.
  bool have_time_ = false;
  std::uint64_t last_controller_us_ = 0;
  std::int64_t offset_us_ = 0;
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
