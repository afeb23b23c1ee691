// MotionGate: standing (slow for long enough), distance travelled, link alive (timeout), refused samples.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "toposlam/segmentation/motion_gate.hpp"

using toposlam::MotionGate;
using toposlam::MotionGateConfig;
using toposlam::MotionState;

namespace {
MotionGateConfig gateConfig() {
  MotionGateConfig c;
  c.standing_speed_mps = 0.05;
  c.standing_after_s = 1.0;
  c.timeout_s = 0.5;
  return c;
}
}  // namespace

TEST_CASE("GIVEN no motion sample WHEN a frame time is asked THEN motion is unknown", "[motion_gate]") {
  const MotionGate gate(gateConfig());
  const MotionState s = gate.at(3.0);
  CHECK_FALSE(s.known);
  CHECK_FALSE(s.standing);
  CHECK(s.distance_m == 0.0);
}

TEST_CASE(
    "GIVEN samples of a moving robot WHEN asked THEN distance is the sum of |increments| and it is not "
    "standing",
    "[motion_gate]") {
  MotionGate gate(gateConfig());
  for (int i = 1; i <= 10; ++i) REQUIRE(gate.addSample(0.1 * i, 0.03, 0.3));
  REQUIRE(gate.addSample(1.1, -0.03, -0.3));  // reversing is travel too
  const MotionState s = gate.at(1.15);
  CHECK(s.known);
  CHECK_FALSE(s.standing);
  CHECK(s.distance_m == Approx(0.33));
  CHECK(gate.samples() == 11);
}

TEST_CASE(
    "GIVEN the robot slows below the threshold WHEN standing_after_s has passed THEN it stands, and not "
    "before",
    "[motion_gate]") {
  MotionGate gate(gateConfig());
  double t = 0.0;
  for (int i = 0; i < 10; ++i) gate.addSample(t += 0.1, 0.03, 0.3);
  // Slow from t = 1.1 on.
  gate.addSample(t += 0.1, 0.0, 0.01);
  const double slow_start = t;
  for (int i = 0; i < 5; ++i) gate.addSample(t += 0.1, 0.0, 0.0);
  CHECK(gate.at(t).known);
  CHECK_FALSE(gate.at(t).standing);  // 0.5 s slow
  for (int i = 0; i < 5; ++i) gate.addSample(t += 0.1, 0.0, 0.0);
  CHECK(t - slow_start >= 1.0 - 1e-9);
  CHECK(gate.at(t).standing);
  // Moving again: not standing at once.
  gate.addSample(t += 0.1, 0.03, 0.3);
  CHECK_FALSE(gate.at(t).standing);
  CHECK(gate.at(t).distance_m == Approx(0.33));
}

TEST_CASE(
    "GIVEN samples stop arriving WHEN timeout_s has passed THEN motion is unknown (link lost), and known "
    "again "
    "after a new sample, and the gap restarts the standing run",
    "[motion_gate]") {
  MotionGate gate(gateConfig());
  double t = 0.0;
  for (int i = 0; i < 20; ++i) gate.addSample(t += 0.1, 0.0, 0.0);
  CHECK(gate.at(t + 0.5).known);
  CHECK(gate.at(t + 0.5).standing);
  CHECK_FALSE(gate.at(t + 0.51).known);
  CHECK_FALSE(gate.at(t + 0.51).standing);
  t += 5.0;
  gate.addSample(t, 0.0, 0.0);
  CHECK(gate.at(t).known);
  CHECK_FALSE(gate.at(t).standing);  // slow only since the link came back
  for (int i = 0; i < 5; ++i) gate.addSample(t += 0.25, 0.0, 0.0);
  CHECK(gate.at(t).standing);
}

TEST_CASE("GIVEN bad samples WHEN added THEN they are refused and counted, the state unchanged",
          "[motion_gate]") {
  MotionGate gate(gateConfig());
  REQUIRE(gate.addSample(1.0, 0.1, 0.3));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(gate.addSample(0.5, 0.1, 0.3));  // time goes back
  CHECK_FALSE(gate.addSample(1.1, nan, 0.3));
  CHECK_FALSE(gate.addSample(1.1, 0.1, std::numeric_limits<double>::infinity()));
  CHECK_FALSE(gate.addSample(nan, 0.1, 0.3));
  CHECK(gate.rejectedSamples() == 4);
  CHECK(gate.samples() == 1);
  CHECK(gate.at(1.2).distance_m == Approx(0.1));
  CHECK_FALSE(gate.at(nan).known);
}

TEST_CASE("GIVEN an out-of-range gate config WHEN validated or used THEN the key and range are named",
          "[motion_gate]") {
  MotionGateConfig c = gateConfig();
  CHECK(c.validate().empty());
  c.timeout_s = 0.0;
  CHECK(c.validate().find("timeout_s") == 0);
  CHECK_THROWS_AS(MotionGate(c), std::invalid_argument);
  c = gateConfig();
  c.standing_speed_mps = -1.0;
  CHECK(c.validate().find("standing_speed_mps") == 0);
  c = gateConfig();
  c.standing_after_s = std::nan("");
  CHECK(c.validate().find("standing_after_s") == 0);
  c = gateConfig();
  c.standing_turn_rate_rps = 101.0;
  CHECK(c.validate().find("standing_turn_rate_rps") == 0);
}

TEST_CASE("GIVEN a robot turning on the spot WHEN asked THEN it is moving, and it stands once the turn ends",
          "[motion_gate]") {
  MotionGate gate(gateConfig());  // standing_turn_rate_rps 0.1 rad/s by default
  double t = 0.0;
  for (int i = 0; i < 20; ++i) REQUIRE(gate.addSample(t += 0.1, 0.0, 0.0, 1.0));  // 2 s at 1 rad/s, no travel
  CHECK(gate.at(t).known);
  CHECK_FALSE(gate.at(t).standing);
  CHECK(gate.at(t).distance_m == 0.0);
  for (int i = 0; i < 5; ++i) gate.addSample(t += 0.1, 0.0, 0.0, 0.05);  // below the turn threshold
  CHECK_FALSE(gate.at(t).standing);  // 0.5 s still
  for (int i = 0; i < 6; ++i) gate.addSample(t += 0.1, 0.0, 0.0, -0.05);
  CHECK(gate.at(t).standing);        // 1.1 s still
  CHECK_FALSE(gate.addSample(t += 0.1, 0.0, 0.0, std::numeric_limits<double>::infinity()));
  CHECK(gate.rejectedSamples() == 1);
}

// Issue 41's poisoning: the samples of a robot that drives 2 s and then stands 3 s, at 50 Hz on the
// receiver's CLOCK_MONOTONIC (1000 s after boot), with one message stamped by a sender's wall clock
// (1.7e9 s, Unix time) in between.
TEST_CASE("GIVEN one sample stamped far in the future WHEN real samples follow THEN it is refused and counted, the "
          "real samples are still used and the stop is still detected",
          "[motion_gate]") {
  MotionGate gate(gateConfig());
  double t = 1000.0;
  for (int i = 0; i < 100; ++i, t += 0.02) REQUIRE(gate.addSample(t, 0.01, 0.5, 0.0, t + 0.001));
  CHECK_FALSE(gate.addSample(1.7e9, 0.01, 0.5, 0.0, t));
  CHECK(gate.refusals().off_clock == 1);
  CHECK(gate.refusedSinceAccepted() == 1);
  int taken = 0;
  for (int i = 0; i < 150; ++i, t += 0.02) taken += gate.addSample(t, 0.0, 0.0, 0.0, t + 0.001) ? 1 : 0;
  CHECK(taken == 150);
  CHECK(gate.refusedSinceAccepted() == 0);
  CHECK(gate.rejectedSamples() == 1);
  CHECK(gate.samples() == 250);
  const MotionState s = gate.at(t);
  CHECK(s.known);
  CHECK(s.standing);  // slow since 1002.0 s, asked at 1005.0 s
  CHECK(s.distance_m == Approx(1.0));
}

TEST_CASE("GIVEN samples off the receiver's clock WHEN added THEN only those beyond clock_tolerance_s are refused, "
          "in both directions, and without a receiver clock nothing is",
          "[motion_gate]") {
  MotionGateConfig c = gateConfig();
  c.clock_tolerance_s = 1.0;
  MotionGate gate(c);
  CHECK(gate.addSample(100.9, 0.0, 0.0, 0.0, 100.0));  // 0.9 s ahead: within
  CHECK_FALSE(gate.addSample(101.2, 0.0, 0.0, 0.0, 100.1));  // 1.1 s ahead
  CHECK_FALSE(gate.addSample(101.0, 0.0, 0.0, 0.0, 102.5));  // 1.5 s behind
  CHECK(gate.refusals().off_clock == 2);
  // Ahead by up to the tolerance, a sample shadows what comes after it for at most that long.
  CHECK_FALSE(gate.addSample(100.5, 0.0, 0.0, 0.0, 100.5));
  CHECK(gate.refusals().earlier == 1);
  CHECK(gate.addSample(101.0, 0.0, 0.0, 0.0, 101.0));
  // A recorded file: no receiver clock (NaN), no check.
  CHECK(gate.addSample(5000.0, 0.0, 0.0));
  CHECK(gate.rejectedSamples() == 3);
  CHECK(gate.samples() == 3);
}

TEST_CASE("GIVEN absurd but well-formed samples (945 km forward, 4.3 million rad/s) WHEN added THEN the "
          "plausibility limits refuse them and the distance stays the robot's",
          "[motion_gate]") {
  MotionGateConfig c = gateConfig();
  c.max_speed_mps = 5.0;
  c.max_turn_rate_rps = 10.0;
  MotionGate gate(c);
  double t = 10.0;
  for (int i = 0; i < 10; ++i, t += 0.02) REQUIRE(gate.addSample(t, 0.01, 0.5, 0.2, t));
  CHECK_FALSE(gate.addSample(t, 945000.0, 0.5, 0.0, t));      // the increment: 5 m/s allows 2.5 m in 0.5 s
  CHECK_FALSE(gate.addSample(t, 0.01, 945000.0 / 0.02, 0.0, t));  // the speed
  CHECK_FALSE(gate.addSample(t, 0.0, 0.0, 4.3e6, t));         // the turn rate
  CHECK_FALSE(gate.addSample(t, 0.0, 0.0, -10.5, t));         // a turn rate just beyond the limit
  CHECK(gate.refusals().implausible == 4);
  CHECK(gate.addSample(t, 2.4, 4.9, 9.9, t));  // just within: 2.4 m after 0.02 s (timeout 0.5 s x 5 m/s)
  t += 3.0;
  CHECK(gate.addSample(t, 14.0, 4.7, 0.0, t));  // 14 m after a 3 s gap: 4.7 m/s
  CHECK(gate.distanceM() == Approx(0.1 + 2.4 + 14.0));
  CHECK(gate.at(t).turned_rad == Approx(0.2 * 0.02 * 9 + 9.9 * 0.02));  // nothing over the 3 s gap
}

TEST_CASE("GIVEN an out-of-range tolerance or limit WHEN validated THEN the key is named", "[motion_gate]") {
  MotionGateConfig c = gateConfig();
  c.clock_tolerance_s = 0.0;
  CHECK(c.validate().find("clock_tolerance_s") == 0);
  c = gateConfig();
  c.max_speed_mps = 0.0;
  CHECK(c.validate().find("max_speed_mps") == 0);
  c = gateConfig();
  c.max_turn_rate_rps = 1001.0;
  CHECK(c.validate().find("max_turn_rate_rps") == 0);
}
