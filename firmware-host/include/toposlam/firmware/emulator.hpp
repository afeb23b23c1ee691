// An emulated robot controller: drives a speed profile (segments of speed and turn rate, with stops) and
// sends what a real controller would on its link, wheel link or MAVLink 2, with the damage of a real
// line: dropped frames, flipped bits, bursts of garbage and silent dropouts. It also keeps the truth
// (distance and turn actually driven) so tests can check what the host made of it.
//
// Plain class: time is passed in (seconds since the emulated controller booted), randomness is seeded;
// the same config gives the same bytes. `toposlam-bridge --emulate` writes it to a pseudo-terminal in
// real time.
#pragma once

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace toposlam::firmware {

struct SpeedSegment {
  double duration_s = 0;
  double speed_mps = 0;     ///< forward
  double turn_rate_rps = 0; ///< counter-clockwise
};

/// "D@V[@W],..." e.g. "10@0.5,10@0,5@0.17@0.2": 10 s at 0.5 m/s, a 10 s stop, 5 s at 0.17 m/s turning
/// 0.2 rad/s. nullopt (and `error`) on a malformed profile.
std::optional<std::vector<SpeedSegment>> parseProfile(const std::string& text, std::string* error = nullptr);

enum class EmulatedMessages {
  WheelOdometry,         ///< wheel link: WHEEL_ODOMETRY, STATUS and HEARTBEAT at 1 Hz
  BodyVelocity,          ///< wheel link: BODY_VELOCITY, STATUS and HEARTBEAT at 1 Hz
  MavlinkOdometry,       ///< MAVLink 2: ODOMETRY, HEARTBEAT at 1 Hz
  MavlinkLocalPosition,  ///< MAVLink 2: LOCAL_POSITION_NED + ATTITUDE, HEARTBEAT at 1 Hz
};
/// wheel-odometry, body-velocity, mavlink-odometry, mavlink-local-position.
std::optional<EmulatedMessages> parseEmulatedMessages(const std::string& name);

struct Dropout {
  double start_s = 0;
  double end_s = 0;  ///< nothing is sent in [start, end)
};

struct EmulatorConfig {
  EmulatedMessages messages = EmulatedMessages::WheelOdometry;
  double rate_hz = 50;                                 ///< motion messages per second
  std::vector<SpeedSegment> profile = {{10, 0.5, 0}};
  double drop_probability = 0;     ///< per frame: not sent
  double corrupt_probability = 0;  ///< per frame: one bit flipped (the host must reject it)
  double garbage_probability = 0;  ///< per frame: 1..64 random bytes sent before it
  std::vector<Dropout> dropouts;
  double track_m = 0.3;            ///< wheel separation of the emulated differential drive
  bool other_mavlink_traffic = false;  ///< with each heartbeat: a MAVLink 1 frame, a signed frame, an unknown id
  std::uint64_t seed = 1;
};

struct EmulatorTruth {
  double distance_m = 0;     ///< driven so far (signed, forward positive)
  double turn_rad = 0;       ///< turned so far (counter-clockwise positive)
  std::uint64_t motion_frames = 0;        ///< motion messages generated
  std::uint64_t motion_frames_intact = 0; ///< of those, sent undamaged
  std::uint64_t frames_dropped = 0;
  std::uint64_t frames_corrupted = 0;
  std::uint64_t garbage_bytes = 0;
  std::uint64_t frames_sent = 0;           ///< all frames written undamaged (motion, heartbeat, status)
};

class ControllerEmulator {
 public:
  explicit ControllerEmulator(EmulatorConfig config);
  /// Runs the controller up to `t_s` and appends the bytes it sent meanwhile to `out`.
  void advanceTo(double t_s, std::vector<std::uint8_t>& out);
  /// Total length of the profile, s.
  double duration() const;
  /// Commanded speed at `t_s` (0 after the profile ends).
  SpeedSegment commandAt(double t_s) const;
  const EmulatorTruth& truth() const { return truth_; }
  const EmulatorConfig& config() const { return config_; }

 private:
  void tick(double t, std::vector<std::uint8_t>& out);
  void emitMotion(double t, std::vector<std::uint8_t>& out);
  void emitHeartbeat(double t, std::vector<std::uint8_t>& out);
  /// Sends one frame through the damaged line; motion frames are counted in the truth.
  void send(const std::uint8_t* frame, std::size_t size, bool motion, std::vector<std::uint8_t>& out);
  bool inDropout(double t) const;

  EmulatorConfig config_;
  EmulatorTruth truth_;
  std::mt19937_64 rng_;
  double time_s_ = 0;       ///< time of the last tick
  std::uint64_t ticks_ = 0;
  double north_ = 0, east_ = 0, heading_ = 0;  ///< NED pose (heading clockwise)
  double left_m_ = 0, right_m_ = 0;
  std::uint8_t seq_ = 0;
  double next_heartbeat_s_ = 0;
  std::uint16_t boot_id_ = 0;
};

}  // namespace toposlam::firmware
