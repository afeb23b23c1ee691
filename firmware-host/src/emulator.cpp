// The emulated controller (see emulator.hpp).
#include "toposlam/firmware/emulator.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "toposlam/firmware/mavlink.hpp"
#include "toposlam_wheel_link.h"

namespace toposlam::firmware {

std::optional<std::vector<SpeedSegment>> parseProfile(const std::string& text, std::string* error) {
  std::vector<SpeedSegment> out;
  std::stringstream all(text);
  std::string item;
  while (std::getline(all, item, ',')) {
    SpeedSegment s;
    double* fields[] = {&s.duration_s, &s.speed_mps, &s.turn_rate_rps};
    std::stringstream parts(item);
    std::string part;
    int n = 0;
    while (std::getline(parts, part, '@')) {
      char* end = nullptr;
      const double v = std::strtod(part.c_str(), &end);
      if (n >= 3 || part.empty() || end == nullptr || *end != '\0' || !std::isfinite(v)) {
        if (error) *error = "bad profile segment '" + item + "': expected DURATION_S@SPEED_MPS[@TURN_RPS]";
        return std::nullopt;
      }
      *fields[n++] = v;
    }
    if (n < 2 || s.duration_s <= 0) {
      if (error) *error = "bad profile segment '" + item + "': expected DURATION_S@SPEED_MPS[@TURN_RPS], duration > 0";
      return std::nullopt;
    }
    out.push_back(s);
  }
  if (out.empty()) {
    if (error) *error = "empty profile";
    return std::nullopt;
  }
  return out;
}

std::optional<EmulatedMessages> parseEmulatedMessages(const std::string& name) {
  if (name == "wheel-odometry" || name == "wheel") return EmulatedMessages::WheelOdometry;
  if (name == "body-velocity") return EmulatedMessages::BodyVelocity;
  if (name == "mavlink-odometry" || name == "mavlink") return EmulatedMessages::MavlinkOdometry;
  if (name == "mavlink-local-position") return EmulatedMessages::MavlinkLocalPosition;
  return std::nullopt;
}

ControllerEmulator::ControllerEmulator(EmulatorConfig config) : config_(std::move(config)), rng_(config_.seed) {
  boot_id_ = static_cast<std::uint16_t>(rng_() & 0xFFFF);
}

double ControllerEmulator::duration() const {
  double d = 0;
  for (const SpeedSegment& s : config_.profile) d += s.duration_s;
  return d;
}

SpeedSegment ControllerEmulator::commandAt(double t) const {
  double start = 0;
  for (const SpeedSegment& s : config_.profile) {
    if (t < start + s.duration_s) return s;
    start += s.duration_s;
  }
  return SpeedSegment{};
}

bool ControllerEmulator::inDropout(double t) const {
  for (const Dropout& d : config_.dropouts)
    if (t >= d.start_s && t < d.end_s) return true;
  return false;
}

void ControllerEmulator::advanceTo(double t_s, std::vector<std::uint8_t>& out) {
  const double period = 1.0 / config_.rate_hz;
  for (;;) {
    const double next = static_cast<double>(ticks_ + 1) * period;
    if (next > t_s + 1e-12) break;
    // Integrate the commanded motion over (time_s_, next] (piecewise constant: sampled mid-step).
    const double dt = next - time_s_;
    const SpeedSegment c = commandAt(time_s_ + 0.5 * dt);
    const double dist = c.speed_mps * dt, turn = c.turn_rate_rps * dt;
    const double mid_heading = heading_ - 0.5 * turn;  // NED heading is clockwise
    north_ += dist * std::cos(mid_heading);
    east_ += dist * std::sin(mid_heading);
    heading_ -= turn;
    left_m_ += dist - 0.5 * turn * config_.track_m;
    right_m_ += dist + 0.5 * turn * config_.track_m;
    truth_.distance_m += dist;
    truth_.turn_rad += turn;
    time_s_ = next;
    ++ticks_;
    tick(next, out);
  }
}

void ControllerEmulator::tick(double t, std::vector<std::uint8_t>& out) {
  if (t >= next_heartbeat_s_) {
    emitHeartbeat(t, out);
    next_heartbeat_s_ += 1.0;
  }
  emitMotion(t, out);
}

void ControllerEmulator::send(const std::uint8_t* frame, std::size_t size, bool motion, std::vector<std::uint8_t>& out) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  if (motion) ++truth_.motion_frames;
  if (inDropout(time_s_) || u(rng_) < config_.drop_probability) {
    ++truth_.frames_dropped;
    return;
  }
  if (u(rng_) < config_.garbage_probability) {
    const std::size_t n = 1 + rng_() % 64;
    for (std::size_t i = 0; i < n; ++i) out.push_back(static_cast<std::uint8_t>(rng_()));
    truth_.garbage_bytes += n;
  }
  const std::size_t at = out.size();
  out.insert(out.end(), frame, frame + size);
  if (u(rng_) < config_.corrupt_probability) {
    out[at + rng_() % size] ^= static_cast<std::uint8_t>(1u << (rng_() % 8));
    ++truth_.frames_corrupted;
    return;
  }
  ++truth_.frames_sent;
  if (motion) ++truth_.motion_frames_intact;
}

void ControllerEmulator::emitHeartbeat(double t, std::vector<std::uint8_t>& out) {
  std::uint8_t frame[mavlink::kMaxFrame];
  const std::uint64_t us = static_cast<std::uint64_t>(std::llround(t * 1e6));
  const SpeedSegment c = commandAt(t);
  if (config_.messages == EmulatedMessages::WheelOdometry || config_.messages == EmulatedMessages::BodyVelocity) {
    twl_heartbeat_t h{us, boot_id_, 1, 0, 0};
    send(frame, twl_encode_heartbeat(frame, sizeof frame, seq_++, &h), false, out);
    twl_status_t s{us, static_cast<std::uint8_t>(c.speed_mps != 0 || c.turn_rate_rps != 0 ? TWL_MODE_DRIVING : TWL_MODE_IDLE),
                   0, 12000, 800, 0};
    send(frame, twl_encode_status(frame, sizeof frame, seq_++, &s), false, out);
    return;
  }
  mavlink::Heartbeat h;
  h.type = 10;       // MAV_TYPE_GROUND_ROVER
  h.autopilot = 12;  // MAV_AUTOPILOT_PX4
  h.base_mode = 0x81;
  h.system_status = 4;  // MAV_STATE_ACTIVE
  mavlink::Header header{seq_++, 1, 1};
  send(frame, mavlink::encode(frame, sizeof frame, header, h), false, out);
  if (config_.other_mavlink_traffic) {
    std::uint8_t payload[255] = {};
    const std::size_t n = mavlink::pack(h, payload);
    header.seq = seq_++;
    send(frame, mavlink::encodeFrameV1(frame, sizeof frame, header, 0, 50, payload, n), false, out);
    header.seq = seq_++;
    send(frame, mavlink::encode(frame, sizeof frame, header, h, /*signed_frame=*/true), false, out);
    // SYS_STATUS-like traffic of an id the host does not know (and so cannot verify).
    for (std::size_t i = 0; i < 31; ++i) payload[i] = static_cast<std::uint8_t>(rng_());
    header.seq = seq_++;
    out.insert(out.end(), frame, frame + mavlink::encodeFrame(frame, sizeof frame, header, 1, 124, payload, 31));
  }
}

void ControllerEmulator::emitMotion(double t, std::vector<std::uint8_t>& out) {
  std::uint8_t frame[mavlink::kMaxFrame];
  const std::uint64_t us = static_cast<std::uint64_t>(std::llround(t * 1e6));
  const SpeedSegment c = commandAt(t - 0.5 / config_.rate_hz);
  switch (config_.messages) {
    case EmulatedMessages::WheelOdometry: {
      const auto wrap = [](double metres) {
        return static_cast<std::int32_t>(static_cast<std::uint32_t>(static_cast<std::int64_t>(std::llround(metres * 1e6))));
      };
      twl_wheel_odometry_t m{us, wrap(left_m_), wrap(right_m_), static_cast<std::uint16_t>(std::lround(config_.track_m * 1000)),
                             static_cast<std::uint8_t>(c.speed_mps != 0 || c.turn_rate_rps != 0 ? TWL_ODOM_DRIVING : 0), 0};
      send(frame, twl_encode_wheel_odometry(frame, sizeof frame, seq_++, &m), true, out);
      break;
    }
    case EmulatedMessages::BodyVelocity: {
      twl_body_velocity_t m{us, static_cast<std::int32_t>(std::lround(c.speed_mps * 1000)), 0,
                            static_cast<std::int32_t>(std::lround(c.turn_rate_rps * 1000))};
      send(frame, twl_encode_body_velocity(frame, sizeof frame, seq_++, &m), true, out);
      break;
    }
    case EmulatedMessages::MavlinkOdometry: {
      mavlink::Odometry m;
      m.time_usec = us;
      m.x = static_cast<float>(north_);
      m.y = static_cast<float>(east_);
      m.q[0] = static_cast<float>(std::cos(0.5 * heading_));
      m.q[3] = static_cast<float>(std::sin(0.5 * heading_));
      m.vx = static_cast<float>(c.speed_mps);
      m.yawspeed = static_cast<float>(-c.turn_rate_rps);
      m.frame_id = mavlink::kFrameLocalNed;
      m.child_frame_id = mavlink::kFrameBodyFrd;
      m.quality = 100;
      send(frame, mavlink::encode(frame, sizeof frame, mavlink::Header{seq_++, 1, 1}, m), true, out);
      break;
    }
    case EmulatedMessages::MavlinkLocalPosition: {
      mavlink::Attitude a;
      a.time_boot_ms = static_cast<std::uint32_t>(us / 1000);
      a.yaw = static_cast<float>(std::remainder(heading_, 2 * 3.14159265358979323846));
      a.yawspeed = static_cast<float>(-c.turn_rate_rps);
      send(frame, mavlink::encode(frame, sizeof frame, mavlink::Header{seq_++, 1, 1}, a), false, out);
      mavlink::LocalPositionNed p;
      p.time_boot_ms = a.time_boot_ms;
      p.x = static_cast<float>(north_);
      p.y = static_cast<float>(east_);
      p.vx = static_cast<float>(c.speed_mps * std::cos(heading_));
      p.vy = static_cast<float>(c.speed_mps * std::sin(heading_));
      send(frame, mavlink::encode(frame, sizeof frame, mavlink::Header{seq_++, 1, 1}, p), true, out);
      break;
    }
  }
}

}  // namespace toposlam::firmware
