// Controller messages -> MotionSample (see motion_estimator.hpp).
#include "toposlam/firmware/motion_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace toposlam::firmware {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Into [-pi, pi] in one step (a loop of 2 pi steps would never end for a yaw of 1e30).
double wrapAngle(double a) { return std::remainder(a, 2 * kPi); }

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

}  // namespace

void MotionEstimator::restart() {
  ++counters_.restarts;
  have_previous_ = false;
  have_time_ = false;
}

bool MotionEstimator::isMoving(double v, double w) const {
  return std::abs(v) > config_.moving_speed_mps || std::abs(w) > config_.moving_turn_rps;
}

// Maps controller time to host time. A controller clock that steps back means a restart: the previous
// sample is forgotten, so this message becomes the new reference. One that runs ahead of the host's is
// refused (see the header).
std::optional<std::int64_t> MotionEstimator::controllerTime(std::uint64_t controller_us, std::int64_t host_us) {
  const auto tolerance_us = static_cast<std::int64_t>(config_.clock_tolerance_s * 1e6);
  const auto refuse = [&]() -> std::optional<std::int64_t> {
    ++counters_.off_clock;
    if (!refused_since_us_) refused_since_us_ = host_us;
    return std::nullopt;
  };
  if (controller_us > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) return refuse();
  const auto controller = static_cast<std::int64_t>(controller_us);
  if (have_time_ && controller_us < last_controller_us_) restart();
  if (have_time_) {
    // Both steps in range: controller times are in [0, 2^63), so their difference is too.
    const std::int64_t controller_step = controller - static_cast<std::int64_t>(last_controller_us_);
    std::int64_t host_step = 0;
    std::int64_t allowed = 0;
    const bool host_overflow = __builtin_sub_overflow(host_us, last_host_us_, &host_step) ||
                               __builtin_add_overflow(host_step, tolerance_us, &allowed);
    if (host_overflow || controller_step > allowed) {
      // Refused, unless the run of refusals has lasted longer than the tolerance: then the controller's
      // clock did jump, and this message starts again from a new reference.
      std::int64_t refusing_for = 0;
      if (!refused_since_us_ || __builtin_sub_overflow(host_us, *refused_since_us_, &refusing_for) ||
          refusing_for <= tolerance_us)
        return refuse();
      restart();
    }
  }
  std::int64_t offset = 0;
  if (__builtin_sub_overflow(host_us, controller, &offset)) return refuse();
  if (!have_time_ || offset < offset_us_) offset_us_ = offset;
  std::int64_t mapped = 0;
  if (__builtin_add_overflow(controller, offset_us_, &mapped)) return refuse();
  // Behind the host by more than the tolerance: the controller's clock runs slow (or the link delivered
  // late); the time is re-estimated from this message.
  std::int64_t behind = 0;
  if (__builtin_sub_overflow(host_us, mapped, &behind) || behind > tolerance_us) {
    ++counters_.clock_resyncs;
    offset_us_ = offset;
    mapped = host_us;
  }
  have_time_ = true;
  last_controller_us_ = controller_us;
  last_host_us_ = host_us;
  refused_since_us_.reset();
  return mapped;
}

std::optional<MotionSample> MotionEstimator::plausible(const MotionSample& s, double dt_s) {
  const double interval_s = std::max(dt_s, config_.max_gap_s);
  // Written so that NaN fails every comparison.
  const bool ok = std::abs(s.linear_velocity_mps) <= config_.max_speed_mps &&
                  std::abs(s.angular_velocity_rps) <= config_.max_turn_rate_rps &&
                  std::hypot(s.forward_m, s.lateral_m) <= config_.max_speed_mps * interval_s &&
                  std::abs(s.turn_rad) <= config_.max_turn_rate_rps * interval_s;
  if (ok) {
    ++counters_.samples;
    return s;
  }
  ++counters_.implausible;
  have_previous_ = false;
  return std::nullopt;
}

std::optional<MotionSample> MotionEstimator::onWheel(const wheel::Message& message, std::int64_t host_us) {
  return std::visit(
      Overloaded{
          [&](const twl_wheel_odometry_t& m) { return wheelOdometry(m, host_us); },
          [&](const twl_body_velocity_t& m) { return bodyVelocity(m, host_us); },
          [&](const twl_heartbeat_t& m) -> std::optional<MotionSample> {
            ++counters_.heartbeats;
            if (boot_id_ && *boot_id_ != m.boot_id) restart();
            boot_id_ = m.boot_id;
            return std::nullopt;
          },
          [&](const twl_status_t& m) -> std::optional<MotionSample> {
            ++counters_.statuses;
            status_ = m;
            return std::nullopt;
          },
          [&](std::monostate) -> std::optional<MotionSample> { return std::nullopt; },
      },
      message);
}

std::optional<MotionSample> MotionEstimator::wheelOdometry(const twl_wheel_odometry_t& m, std::int64_t host_us) {
  if (m.track_mm == 0) {
    ++counters_.invalid;
    return std::nullopt;
  }
  const std::optional<std::int64_t> utime = controllerTime(m.time_us, host_us);
  if (!utime) return std::nullopt;
  const bool first = !have_previous_;
  // Wrapping differences: the counters are modulo 2^32 (C++20 conversions are modular).
  const auto left_step_um = static_cast<std::int32_t>(static_cast<std::uint32_t>(m.left_um) -
                                                      static_cast<std::uint32_t>(prev_left_um_));
  const auto right_step_um = static_cast<std::int32_t>(static_cast<std::uint32_t>(m.right_um) -
                                                       static_cast<std::uint32_t>(prev_right_um_));
  const double dl = left_step_um * 1e-6;
  const double dr = right_step_um * 1e-6;
  const double dt = (static_cast<double>(m.time_us) - static_cast<double>(prev_controller_us_)) * 1e-6;
  prev_left_um_ = m.left_um;
  prev_right_um_ = m.right_um;
  prev_controller_us_ = m.time_us;
  have_previous_ = true;
  if (first) return std::nullopt;
  MotionSample s;
  s.utime = *utime;
  s.forward_m = 0.5 * (dl + dr);
  // The wheels' difference in integer micrometres, so equal steps give exactly no turn on every CPU: from
  // dr - dl, GCC on aarch64 fuses one product into the subtraction (fma) and leaves its rounding error.
  s.turn_rad = static_cast<double>(static_cast<std::int64_t>(right_step_um) - left_step_um) * 1e-6 /
               (m.track_mm * 1e-3);
  if (dt > 0) {
    s.linear_velocity_mps = s.forward_m / dt;
    s.angular_velocity_rps = s.turn_rad / dt;
  }
  s.moving = (m.flags & TWL_ODOM_DRIVING) != 0 || isMoving(s.linear_velocity_mps, s.angular_velocity_rps);
  return plausible(s, dt);
}

std::optional<MotionSample> MotionEstimator::bodyVelocity(const twl_body_velocity_t& m, std::int64_t host_us) {
  const std::optional<std::int64_t> utime = controllerTime(m.time_us, host_us);
  if (!utime) return std::nullopt;
  const double vx = m.vx_mm_s * 1e-3, vy = m.vy_mm_s * 1e-3, wz = m.wz_mrad_s * 1e-3;
  const bool first = !have_previous_;
  const double dt = (static_cast<double>(m.time_us) - static_cast<double>(prev_controller_us_)) * 1e-6;
  MotionSample s;
  s.utime = *utime;
  if (!first) {
    if (dt <= config_.max_gap_s) {
      s.forward_m = 0.5 * (prev_vx_ + vx) * dt;
      s.lateral_m = 0.5 * (prev_vy_ + vy) * dt;
      s.turn_rad = 0.5 * (prev_wz_ + wz) * dt;
    } else {
      ++counters_.gaps;
    }
  }
  prev_vx_ = vx;
  prev_vy_ = vy;
  prev_wz_ = wz;
  prev_controller_us_ = m.time_us;
  have_previous_ = true;
  if (first) return std::nullopt;
  s.linear_velocity_mps = vx;
  s.angular_velocity_rps = wz;
  s.moving = isMoving(vx, wz) || std::abs(vy) > config_.moving_speed_mps;
  return plausible(s, dt);
}

std::optional<MotionSample> MotionEstimator::onMavlink(const mavlink::Message& message, std::int64_t host_us) {
  return std::visit(
      Overloaded{
          [&](const mavlink::Odometry& m) { return odometry(m, host_us); },
          [&](const mavlink::LocalPositionNed& m) { return localPosition(m, host_us); },
          [&](const mavlink::Attitude& m) -> std::optional<MotionSample> {
            attitude_ = m;
            return std::nullopt;
          },
          [&](const mavlink::Heartbeat&) -> std::optional<MotionSample> {
            ++counters_.heartbeats;
            return std::nullopt;
          },
          [&](std::monostate) -> std::optional<MotionSample> { return std::nullopt; },
      },
      message);
}

std::optional<MotionSample> MotionEstimator::odometry(const mavlink::Odometry& m, std::int64_t host_us) {
  using namespace mavlink;
  const bool ned_position = m.frame_id == kFrameLocalNed || m.frame_id == kFrameLocalFrd;
  if (!ned_position || !std::isfinite(m.x) || !std::isfinite(m.y) || !std::isfinite(m.q[0])) {
    ++counters_.invalid;
    return std::nullopt;
  }
  odometry_seen_ = true;
  if (reset_counter_ && *reset_counter_ != m.reset_counter) restart();
  reset_counter_ = m.reset_counter;
  const double w = m.q[0], x = m.q[1], y = m.q[2], z = m.q[3];
  const double yaw = std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
  // Forward speed: body-frame velocity as is; local-frame velocity rotated into the body.
  double forward = 0;
  if (m.child_frame_id == kFrameBodyFrd)
    forward = m.vx;
  else
    forward = m.vx * std::cos(yaw) + m.vy * std::sin(yaw);
  if (!std::isfinite(forward)) forward = 0;
  const double yaw_rate = std::isfinite(m.yawspeed) ? m.yawspeed : 0.0;
  return fromPose(m.time_usec, m.x, m.y, yaw, forward, yaw_rate, host_us);
}

std::optional<MotionSample> MotionEstimator::localPosition(const mavlink::LocalPositionNed& m, std::int64_t host_us) {
  if (odometry_seen_ || !attitude_) return std::nullopt;
  if (!std::isfinite(m.x) || !std::isfinite(m.y) || !std::isfinite(attitude_->yaw)) {
    ++counters_.invalid;
    return std::nullopt;
  }
  const double yaw = attitude_->yaw;
  const double forward = m.vx * std::cos(yaw) + m.vy * std::sin(yaw);
  return fromPose(static_cast<std::uint64_t>(m.time_boot_ms) * 1000, m.x, m.y, yaw, forward,
                  attitude_->yawspeed, host_us);
}

std::optional<MotionSample> MotionEstimator::fromPose(std::uint64_t controller_us, double north, double east,
                                                      double yaw, double forward_speed, double yaw_rate_ned,
                                                      std::int64_t host_us) {
  const std::optional<std::int64_t> utime = controllerTime(controller_us, host_us);
  if (!utime) return std::nullopt;
  const double dt = (static_cast<double>(controller_us) - static_cast<double>(prev_controller_us_)) * 1e-6;
  const bool first = !have_previous_;
  const double dn = north - prev_north_, de = east - prev_east_;
  const double dyaw = wrapAngle(yaw - prev_yaw_);
  const double heading = prev_yaw_;
  prev_north_ = north;
  prev_east_ = east;
  prev_yaw_ = yaw;
  prev_controller_us_ = controller_us;
  have_previous_ = true;
  if (first) return std::nullopt;
  MotionSample s;
  s.utime = *utime;
  // NED -> body at the previous heading: forward along the heading, right 90 degrees clockwise of it.
  s.forward_m = dn * std::cos(heading) + de * std::sin(heading);
  const double right = -dn * std::sin(heading) + de * std::cos(heading);
  s.lateral_m = -right;
  s.turn_rad = -dyaw;  // NED yaw is clockwise seen from above
  s.linear_velocity_mps = forward_speed;
  s.angular_velocity_rps = -yaw_rate_ned;
  s.moving = isMoving(s.linear_velocity_mps, s.angular_velocity_rps);
  return plausible(s, dt);
}

}  // namespace toposlam::firmware
