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
