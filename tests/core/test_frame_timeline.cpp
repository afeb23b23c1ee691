// FrameTimeline (docs/reliability.md, "Clock jumps"): a source's timestamps that step back are carried on
// from the previous frame at the typical interval, then keep their own spacing; forward jumps are gaps.
#include <cmath>
#include <limits>
#include <vector>

#include <catch2/catch.hpp>

#include "toposlam/core/frame_timeline.hpp"

using toposlam::FrameTimeline;

namespace {
constexpr double kDt = 1.0 / 15.0;  // a camera at 15 fps
}  // namespace

TEST_CASE("GIVEN increasing timestamps WHEN placed THEN they are the timeline unchanged",
          "[core][reliability]") {
  FrameTimeline timeline;
  for (int f = 0; f < 100; ++f) {
    const double t = 1000.0 + f * kDt + (f % 3 == 0 ? 0.004 : 0.0);  // jitter forward is kept
    REQUIRE(timeline.place(t) == t);
  }
  CHECK(timeline.stepsBack() == 0);
  CHECK(timeline.repeated() == 0);
  CHECK(timeline.offsetS() == 0.0);
}

TEST_CASE(
    "GIVEN a 15 fps camera clock stepped back 30 s at frame 100 WHEN placed THEN frame 100 comes one frame "
    "interval after frame 99 and the frames after it keep their spacing",
    "[core][reliability]") {
  FrameTimeline timeline;
  std::vector<double> placed;
  for (int f = 0; f < 300; ++f) {
    const double source = 500.0 + f * kDt - (f >= 100 ? 30.0 : 0.0);
    placed.push_back(timeline.place(source));
  }
  for (int f = 1; f < 300; ++f) REQUIRE(placed[f] - placed[f - 1] == Approx(kDt).margin(1e-9));
  CHECK(placed[299] == Approx(500.0 + 299 * kDt).margin(1e-9));  // as if the clock had never stepped
  CHECK(timeline.stepsBack() == 1);
  CHECK(timeline.lastStepBackS() == Approx(30.0 - kDt).margin(1e-9));
  CHECK(timeline.offsetS() == Approx(30.0).margin(1e-9));
}

TEST_CASE("GIVEN a clock stepped forward an hour WHEN placed THEN the gap is kept (it may be a real one)",
          "[core][reliability]") {
  FrameTimeline timeline;
  for (int f = 0; f < 50; ++f) REQUIRE(timeline.place(f * kDt) == f * kDt);
  CHECK(timeline.place(3600.0 + 50 * kDt) == 3600.0 + 50 * kDt);
  CHECK(timeline.place(3600.0 + 51 * kDt) == 3600.0 + 51 * kDt);
  CHECK(timeline.stepsBack() == 0);
  // One huge interval does not make the typical one: the median of the last 8.
  CHECK(timeline.typicalIntervalS() == Approx(kDt));
  // Stepped back again after the forward jump: one frame interval, not an hour.
  CHECK(timeline.place(52 * kDt) == Approx(3600.0 + 52 * kDt));
}

TEST_CASE(
    "GIVEN a source without timestamps (all 0) or with NaN WHEN placed THEN one second apart, and a clock "
    "that resumes after NaN keeps going forward",
    "[core][reliability]") {
  FrameTimeline zeros;
  for (int f = 0; f < 5; ++f) REQUIRE(zeros.place(0.0) == static_cast<double>(f));
  CHECK(zeros.repeated() == 4);
  CHECK(zeros.stepsBack() == 0);

  FrameTimeline gaps;
  CHECK(gaps.place(std::numeric_limits<double>::quiet_NaN()) == 0.0);
  CHECK(gaps.place(10.0) == 10.0);
  CHECK(gaps.place(10.5) == 10.5);
  CHECK(gaps.place(std::numeric_limits<double>::infinity()) == 11.0);  // the lower median of 10 and 0.5 s
  CHECK(gaps.place(11.5) == 11.5);
  CHECK(gaps.repeated() == 2);
}

TEST_CASE("GIVEN small backward jitter and repeats WHEN placed THEN the timeline still strictly increases",
          "[core][reliability]") {
  FrameTimeline timeline;
  double last = -1.0;
  int steps = 0;
  for (int f = 0; f < 1000; ++f) {
    double source = f * kDt;
    if (f % 50 == 7) source -= 0.002;  // 2 ms earlier than its predecessor's spacing implies: still later
    if (f % 97 == 3) source -= 0.1;    // out of order: earlier than the frame before
    const double t = timeline.place(source);
    REQUIRE(t > last);
    steps += f % 97 == 3 ? 1 : 0;
    last = t;
  }
  CHECK(timeline.stepsBack() == steps);
  // Every step back adds about one interval: the timeline ends within a frame per step of the source's.
  CHECK(last - 999 * kDt >= 0.0);
  CHECK(last - 999 * kDt <= (steps + 1) * (kDt + 0.1));
}
