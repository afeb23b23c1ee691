// From controller messages to robot motion, and the emulated controller through the whole host side
// (bytes -> decoder -> estimator), with stops, speed changes, drops, bit errors and garbage.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "toposlam/firmware/emulator.hpp"
#include "toposlam/firmware/motion_link.hpp"

using namespace toposlam::firmware;

namespace {

struct Totals {
  double forward = 0, lateral = 0, turn = 0;
  int samples = 0, moving = 0, standing = 0;
};

Totals runEmulator(const EmulatorConfig& config, LinkProtocol protocol, std::vector<MotionSample>* out = nullptr) {
  ControllerEmulator emulator(config);
  MotionLink link(protocol);
  Totals t;
  std::vector<std::uint8_t> bytes;
  const double step = 0.05;  // the host reads every 50 ms
  for (double now = step; now <= emulator.duration() + 1e-9; now += step) {
    bytes.clear();
    emulator.advanceTo(now, bytes);
    link.feed(bytes, static_cast<std::int64_t>(now * 1e6) + 1000, [&](const MotionSample& s) {
      t.forward += s.forward_m;
      t.lateral += s.lateral_m;
      t.turn += s.turn_rad;
      ++t.samples;
      (s.moving ? t.moving : t.standing) += 1;
      if (out) out->push_back(s);
    });
  }
  return t;
}

}  // namespace

TEST_CASE("GIVEN wheel odometry WHEN the robot drives straight, turns and the counters wrap THEN the increments "
          "follow",
          "[firmware][motion]") {
  MotionEstimator e;
  twl_wheel_odometry_t m{1000000, 0, 0, 300, TWL_ODOM_DRIVING, 0};
  CHECK_FALSE(e.onWheel(m, 5000000).has_value());  // the first message is the reference
  m.time_us += 100000;
  m.left_um = 50000;
  m.right_um = 50000;
  auto s = e.onWheel(m, 5100000 + 300);
  REQUIRE(s);
  CHECK(s->forward_m == Approx(0.05));
  CHECK(s->turn_rad == Approx(0.0));
  CHECK(s->linear_velocity_mps == Approx(0.5));
  CHECK(s->moving);
  CHECK(s->utime == 5100000);  // controller 1.1 s + the smallest offset seen (4 s)

  // Turning on the spot, counter-clockwise: right wheel forward, left back; 0.3 m track.
  m.time_us += 100000;
  m.left_um -= 15000;
  m.right_um += 15000;
  s = e.onWheel(m, 5200000);
  REQUIRE(s);
  CHECK(s->forward_m == Approx(0.0).margin(1e-12));
  CHECK(s->turn_rad == Approx(0.1));

  // The left counter wraps past INT32_MAX: the difference is still +10 mm.
  MotionEstimator w;
  twl_wheel_odometry_t a{0, 2147480000, 0, 300, 0, 0};
  w.onWheel(a, 0);
  a.time_us = 100000;
  a.left_um = static_cast<std::int32_t>(2147480000u + 10000u);
  a.right_um = 10000;
  s = w.onWheel(a, 100000);
  REQUIRE(s);
  CHECK(s->forward_m == Approx(0.01));
  CHECK_FALSE(s->moving == false);  // 0.1 m/s > threshold although the flag says idle
}

TEST_CASE("GIVEN a controller that restarts WHEN its clock steps back THEN no increment spans the restart",
          "[firmware][motion]") {
  MotionEstimator e;
  twl_wheel_odometry_t m{5000000, 1000000, 1000000, 300, 0, 0};
  e.onWheel(m, 10000000);
  m.time_us = 5100000;
  CHECK(e.onWheel(m, 10100000));
  // Restart: clock and counters back near zero. A naive difference would be -1 m.
  m.time_us = 200000;
  m.left_um = m.right_um = 0;
  CHECK_FALSE(e.onWheel(m, 10300000).has_value());
  m.time_us = 300000;
  m.left_um = m.right_um = 20000;
  const auto s = e.onWheel(m, 10400000);
  REQUIRE(s);
  CHECK(s->forward_m == Approx(0.02));
  CHECK(s->utime == 10400000);  // re-mapped: the new offset is 10.1 s
  CHECK(e.counters().restarts == 1);
}

TEST_CASE("GIVEN body velocities WHEN integrated THEN trapezoids, and a long gap is not invented", "[firmware][motion]") {
  MotionEstimator e;
  twl_body_velocity_t v{0, 1000, 0, 500};
  e.onWheel(v, 0);
  v.time_us = 100000;
  auto s = e.onWheel(v, 100000);
  REQUIRE(s);
  CHECK(s->forward_m == Approx(0.1));
  CHECK(s->turn_rad == Approx(0.05));
  v.time_us = 2000000;  // 1.9 s of silence: longer than max_gap_s
  s = e.onWheel(v, 2000000);
  REQUIRE(s);
  CHECK(s->forward_m == 0.0);
  CHECK(e.counters().gaps == 1);
}

TEST_CASE("GIVEN MAVLink ODOMETRY heading east WHEN the drone moves east and yaws right THEN forward and a clockwise "
          "(negative) turn",
          "[firmware][motion]") {
  MotionEstimator e;
  mavlink::Odometry o;
  const double yaw = 3.14159265358979 / 2;  // facing east (NED yaw is clockwise from north)
  o.q[0] = static_cast<float>(std::cos(yaw / 2));
  o.q[3] = static_cast<float>(std::sin(yaw / 2));
  o.time_usec = 1000000;
  e.onMavlink(o, 1000000);
  o.time_usec = 1100000;
  o.y = 0.2f;  // east
  const double yaw2 = yaw + 0.1;
  o.q[0] = static_cast<float>(std::cos(yaw2 / 2));
  o.q[3] = static_cast<float>(std::sin(yaw2 / 2));
  o.vx = 2.0f;
  o.yawspeed = 1.0f;
  const auto s = e.onMavlink(o, 1100000);
  REQUIRE(s);
  CHECK(s->forward_m == Approx(0.2).margin(1e-6));
  CHECK(s->lateral_m == Approx(0.0).margin(1e-6));
  CHECK(s->turn_rad == Approx(-0.1).margin(1e-6));
  CHECK(s->linear_velocity_mps == Approx(2.0));
  CHECK(s->angular_velocity_rps == Approx(-1.0));

  AND_THEN("a position in an unsupported frame is refused and counted") {
    o.frame_id = 4;  // MAV_FRAME_LOCAL_ENU
    CHECK_FALSE(e.onMavlink(o, 1200000));
    CHECK(e.counters().invalid == 1);
  }
}

TEST_CASE("GIVEN wheel odometry at 50 Hz WHEN two checksummed frames carry controller time 2^62 (or beyond int64) "
          "THEN they are refused and counted with no overflow, and the real frames go on on the host's clock",
          "[firmware][motion]") {
  for (const std::uint64_t bogus : {std::uint64_t{1} << 62, std::uint64_t{1} << 63, ~std::uint64_t{0}}) {
    INFO("controller time " << bogus);
    MotionEstimator e;  // clock_tolerance_s 1 s
    twl_wheel_odometry_t m{2000000, 0, 0, 300, TWL_ODOM_DRIVING, 0};
    std::int64_t host = 7000000000;  // host CLOCK_MONOTONIC 7000 s, controller 2 s
    e.onWheel(m, host);
    for (int i = 0; i < 10; ++i) {
      m.time_us += 20000;
      m.left_um += 10000;
      m.right_um += 10000;
      host += 20000;
      const auto s = e.onWheel(m, host);
      REQUIRE(s);
      CHECK(s->utime == host);
    }
    twl_wheel_odometry_t poison = m;
    poison.time_us = bogus;
    poison.left_um += 10000;
    poison.right_um += 10000;
    CHECK_FALSE(e.onWheel(poison, host + 100));
    CHECK_FALSE(e.onWheel(poison, host + 200));
    CHECK(e.counters().off_clock == 2);
    CHECK(e.counters().restarts == 0);
    // The next real frame: 40 ms of controller time after the last accepted one, 0.5 mm of travel each.
    m.time_us += 40000;
    m.left_um += 20000;
    m.right_um += 20000;
    host += 40000;
    const auto s = e.onWheel(m, host);
    REQUIRE(s);
    CHECK(s->utime == host);
    CHECK(s->forward_m == Approx(0.02));
    CHECK(s->linear_velocity_mps == Approx(0.5));
    CHECK(e.counters().samples == 11);
  }
}

TEST_CASE("GIVEN a controller clock that jumps ahead for good WHEN its frames go on for longer than the tolerance "
          "THEN it counts as a restart and the frames are used again, stamped on the host's clock",
          "[firmware][motion]") {
  MotionEstimator e;
  twl_wheel_odometry_t m{1000000, 0, 0, 300, 0, 0};
  std::int64_t host = 50000000;
  e.onWheel(m, host);
  m.time_us += 3600000000;  // one hour ahead, and on from there at 10 Hz
  int refused = 0;
  std::optional<MotionSample> s;
  for (int i = 0; i < 20 && !s; ++i) {
    host += 100000;
    m.time_us += 100000;
    m.left_um += 5000;
    m.right_um += 5000;
    s = e.onWheel(m, host);
    refused += s ? 0 : 1;
  }
  // Refused for 1.1 s (more than the 1 s tolerance), then the new reference, then a sample.
  CHECK(e.counters().off_clock == 11);
  CHECK(e.counters().restarts == 1);
  CHECK(refused == 12);
  REQUIRE(s);
  CHECK(s->utime == host);
  CHECK(s->forward_m == Approx(0.005));
}

TEST_CASE("GIVEN one checksummed frame stamped in the past (time 0) WHEN real 50 Hz frames follow THEN it is taken "
          "as a restart and the real frames are refused for at most clock_tolerance_s, then used again",
          "[firmware][motion]") {
  MotionEstimator e;
  twl_wheel_odometry_t m{600000000, 0, 0, 300, 0, 0};  // the controller has been up 10 minutes
  std::int64_t host = 9000000000;
  e.onWheel(m, host);
  twl_wheel_odometry_t past = m;
  past.time_us = 0;
  host += 10000;
  CHECK_FALSE(e.onWheel(past, host));
  CHECK(e.counters().restarts == 1);
  int lost = 0;
  std::optional<MotionSample> s;
  for (int i = 0; i < 100 && !s; ++i) {
    m.time_us += 20000;
    m.left_um += 10000;
    m.right_um += 10000;
    host += 20000;
    s = e.onWheel(m, host);
    lost += s ? 0 : 1;
  }
  REQUIRE(s);
  CHECK(s->utime == host);
  CHECK(lost == 52);  // 1.0 s of refusals (51 frames), then the new reference
  CHECK(e.counters().restarts == 2);
}

TEST_CASE("GIVEN a controller clock that runs slow WHEN the mapped time falls behind the host's by more than the "
          "tolerance THEN the offset is re-estimated, so a published time stays within it",
          "[firmware][motion]") {
  MotionEstimator e;
  twl_body_velocity_t v{0, 100, 0, 0};
  std::int64_t host = 1000000;
  e.onWheel(v, host);
  std::int64_t worst_behind = 0;
  for (int i = 0; i < 6000; ++i) {  // 20 minutes at 5 Hz; the controller loses 1 ms per second
    v.time_us += 199800;
    host += 200000;
    const auto s = e.onWheel(v, host);
    REQUIRE(s);
    worst_behind = std::max(worst_behind, host - s->utime);
  }
  // 1 s behind after 16 min 40 s: re-estimated once, then 0.2 s behind again by the end.
  CHECK(worst_behind <= 1000000);
  CHECK(e.counters().clock_resyncs == 1);
  CHECK(e.counters().off_clock == 0);
}

TEST_CASE("GIVEN checksummed frames with absurd values WHEN estimated THEN the plausibility limits refuse them "
          "(counted) and no increment spans them",
          "[firmware][motion]") {
  SECTION("wheel odometry: both counters jump 2^31 um the opposite way on a 1 mm track: 4.3 million rad") {
    MotionEstimator e;
    twl_wheel_odometry_t m{1000000, 0, 0, 1, 0, 0};
    e.onWheel(m, 1000000);
    m.time_us += 20000;
    m.left_um = std::numeric_limits<std::int32_t>::min();
    m.right_um = std::numeric_limits<std::int32_t>::max();
    CHECK_FALSE(e.onWheel(m, 1020000));
    CHECK(e.counters().implausible == 1);
    // The next frame is the new reference; the one after is a sample again.
    m.time_us += 20000;
    CHECK_FALSE(e.onWheel(m, 1040000));
    m.time_us += 20000;
    // 0.1 mm on: the right counter wraps past INT32_MAX, as a cumulative counter on the wire does.
    m.left_um += 100;
    m.right_um = static_cast<std::int32_t>(static_cast<std::uint32_t>(m.right_um) + 100u);
    const auto s = e.onWheel(m, 1060000);
    REQUIRE(s);
    CHECK(s->forward_m == Approx(0.0001));
    CHECK(s->turn_rad == 0.0);
  }
  SECTION("MAVLink ODOMETRY: the position jumps 945 km") {
    MotionEstimator e;
    mavlink::Odometry o;
    o.time_usec = 1000000;
    e.onMavlink(o, 1000000);
    o.time_usec = 1020000;
    o.x = 945000.0f;
    CHECK_FALSE(e.onMavlink(o, 1020000));
    CHECK(e.counters().implausible == 1);
    CHECK(e.counters().samples == 0);
  }
  SECTION("body velocity: 2^31 mm/s forward, then 4.3 million mrad/s") {
    MotionEstimator e;
    twl_body_velocity_t v{0, 0, 0, 0};
    e.onWheel(v, 0);
    v.time_us = 20000;
    v.vx_mm_s = std::numeric_limits<std::int32_t>::max();
    CHECK_FALSE(e.onWheel(v, 20000));
    v.vx_mm_s = 500;
    v.time_us = 40000;
    CHECK_FALSE(e.onWheel(v, 40000));  // the new reference
    v.time_us = 60000;
    v.wz_mrad_s = 4300000;
    CHECK_FALSE(e.onWheel(v, 60000));
    CHECK(e.counters().implausible == 2);
  }
  SECTION("just within the limits: 4.9 m/s and 9.9 rad/s are the robot's") {
    MotionEstimator e;
    twl_body_velocity_t v{0, 4900, 0, 9900};
    e.onWheel(v, 0);
    v.time_us = 20000;
    const auto s = e.onWheel(v, 20000);
    REQUIRE(s);
    CHECK(s->forward_m == Approx(0.098));
    CHECK(e.counters().implausible == 0);
  }
}

TEST_CASE("GIVEN the emulated office route with three stops and a slow stretch WHEN sent over each link with damage "
          "THEN the host's distance and standing time match the truth",
          "[firmware][motion][emulator]") {
  EmulatorConfig c;
  // 20 s at 0.5 m/s, a 10 s stop, 15 s at a third of the speed, a 10 s stop, a turn, 10 s at 0.5, a stop.
  c.profile = *parseProfile("20@0.5,10@0,15@0.1667,10@0,3@0@0.5236,10@0.5,10@0");
  c.rate_hz = 50;
  c.garbage_probability = 0.05;
  c.corrupt_probability = 0.02;
  c.drop_probability = 0.02;
  c.seed = 7;
  const double truth_distance = 20 * 0.5 + 15 * 0.1667 + 10 * 0.5;

  SECTION("wheel odometry: cumulative counters lose no distance to drops") {
    c.messages = EmulatedMessages::WheelOdometry;
    std::vector<MotionSample> samples;
    const Totals t = runEmulator(c, LinkProtocol::Wheel, &samples);
    // Exact but for the travel before the first frame that got through (the reference): one 20 ms step.
    CHECK(t.forward == Approx(truth_distance).margin(0.5 * 0.02 + 1e-3));
    CHECK(t.turn == Approx(3 * 0.5236).margin(1e-3));
    // About 30 s of 78 standing, at 50 Hz minus drops and damage.
    CHECK(t.standing > 30 * 50 * 0.85);
    CHECK(t.standing < 30 * 50 * 1.02);
  }
  SECTION("body velocity: integrated, losing only what the drops hid") {
    c.messages = EmulatedMessages::BodyVelocity;
    const Totals t = runEmulator(c, LinkProtocol::Wheel);
    CHECK(t.forward == Approx(truth_distance).margin(0.02 * truth_distance));
  }
  SECTION("MAVLink ODOMETRY, with MAVLink 1, signed and unknown traffic around it") {
    c.messages = EmulatedMessages::MavlinkOdometry;
    c.other_mavlink_traffic = true;
    const Totals t = runEmulator(c, LinkProtocol::Mavlink);
    CHECK(t.forward == Approx(truth_distance).margin(1e-3 * truth_distance));
    CHECK(t.turn == Approx(3 * 0.5236).margin(1e-3));
  }
  SECTION("MAVLink LOCAL_POSITION_NED + ATTITUDE") {
    c.messages = EmulatedMessages::MavlinkLocalPosition;
    const Totals t = runEmulator(c, LinkProtocol::Mavlink);
    CHECK(t.forward == Approx(truth_distance).margin(1e-3 * truth_distance));
  }
}

TEST_CASE("GIVEN the same config WHEN the emulator runs twice THEN the bytes are identical", "[firmware][emulator]") {
  EmulatorConfig c;
  c.garbage_probability = 0.3;
  c.corrupt_probability = 0.1;
  c.seed = 99;
  ControllerEmulator a(c), b(c);
  std::vector<std::uint8_t> x, y;
  a.advanceTo(3.0, x);
  b.advanceTo(3.0, y);
  CHECK(x == y);
  CHECK(a.truth().motion_frames == 150);
  std::string error;
  CHECK_FALSE(parseProfile("10@", &error));
  CHECK_FALSE(parseProfile("0@1", &error));
  CHECK_FALSE(parseProfile("1@2@3@4", &error));
  CHECK(parseProfile("1@2@3")->at(0).turn_rate_rps == 3.0);
}
