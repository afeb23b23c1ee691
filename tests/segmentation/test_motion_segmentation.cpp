// Motion-aware segmentation (docs/segmentation.md, "Motion-aware segmentation"): a synthetic route through
// rooms whose views change with the distance travelled. A long stop (the same view repeated) makes a
// spurious place with the time window alone; with motion (MotionGate -> FiedlerSegmenter) standing frames
// are left out and the window spans metres, and the places equal the rooms. Without motion input the
// motion-aware path is bit-identical to the time-based one.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "fake_similarity.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"
#include "toposlam/segmentation/motion_gate.hpp"

using toposlam::FiedlerSegmenter;
using toposlam::FiedlerSegmenterConfig;
using toposlam::MotionGate;
using toposlam::MotionGateConfig;
using toposlam::MotionState;
using toposlam::SegmentedPlace;
using toposlam::test::fakeFingerprint;
using toposlam::test::TableSimilarity;

namespace {

constexpr double kFps = 5.0;
constexpr double kRoomM = 6.0;

/// One frame of the route: its time, position along the route (metres) and the robot's speed.
struct RouteFrame {
  double time_s;
  double position_m;
  double speed_mps;
};

/// `rooms` rooms of kRoomM metres at `speed` m/s; `stops` (position, seconds) hold the robot still;
/// `slow` (from, to) metres are driven at a third of the speed.
std::vector<RouteFrame> route(int rooms, double speed, const std::vector<std::pair<double, double>>& stops,
                              std::pair<double, double> slow = {-1.0, -1.0}) {
  std::vector<RouteFrame> frames;
  double t = 0.0, x = 0.0;
  std::size_t next_stop = 0;
  const double end = rooms * kRoomM;
  while (x < end) {
    if (next_stop < stops.size() && x >= stops[next_stop].first) {
      const int n = static_cast<int>(stops[next_stop].second * kFps);
      for (int i = 0; i < n; ++i) {
        frames.push_back({t, x, 0.0});
        t += 1.0 / kFps;
      }
      ++next_stop;
    }
    const double v = (x >= slow.first && x < slow.second) ? speed / 3.0 : speed;
    frames.push_back({t, x, v});
    t += 1.0 / kFps;
    x += v / kFps;
  }
  return frames;
}

/// Views of one room fade with the distance between them (e^(-d / 0.8 m), a small deterministic wobble so
/// no two windows tie); views of different rooms hardly match.
TableSimilarity routeSimilarity(const std::vector<RouteFrame>& frames) {
  return TableSimilarity([&frames](int a, int b) {
    const double xa = frames[static_cast<std::size_t>(a)].position_m;
    const double xb = frames[static_cast<std::size_t>(b)].position_m;
    if (std::floor(xa / kRoomM) != std::floor(xb / kRoomM)) return 0.03;
    return std::exp(-std::abs(xa - xb) / 0.8) * (0.97 + 0.02 * std::sin(0.7 * a + 1.3 * b));
  });
}

FiedlerSegmenterConfig timeConfig() {
  FiedlerSegmenterConfig c;  // the daemon's shipped segmentation settings
  c.window_s = 6.0;
  c.window = 100;
  c.min_window_frames = 5;
  c.valley = {0.5, 0.30};
  return c;
}

struct Result {
  std::vector<SegmentedPlace> places;
  std::vector<std::optional<double>> lambda2;
  std::int64_t skipped = 0;
  std::int64_t thinned = 0;
};

/// Segments the route; with `gate`, motion samples (one per frame, at the frame's time) go through it.
Result segment(const std::vector<RouteFrame>& frames, const FiedlerSegmenterConfig& config, MotionGate* gate,
               double link_lost_after_s = 1e9) {
  const TableSimilarity similarity = routeSimilarity(frames);
  FiedlerSegmenter segmenter(config, similarity);
  Result r;
  double previous_x = 0.0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const RouteFrame& f = frames[i];
    const auto frame = static_cast<std::int64_t>(i);
    toposlam::SegmenterStep step;
    if (gate) {
      if (f.time_s < link_lost_after_s) gate->addSample(f.time_s, f.position_m - previous_x, f.speed_mps);
      previous_x = f.position_m;
      step = segmenter.addFrame(frame, f.time_s, fakeFingerprint(static_cast<int>(i)), gate->at(f.time_s));
    } else {
      step = segmenter.addFrame(frame, f.time_s, fakeFingerprint(static_cast<int>(i)));
    }
    r.lambda2.push_back(step.lambda2);
    if (step.closed_place) r.places.push_back(*step.closed_place);
  }
  if (auto last = segmenter.flush()) r.places.push_back(*last);
  r.skipped = segmenter.skippedFrames();
  r.thinned = segmenter.thinnedFrames();
  return r;
}

MotionGateConfig gateConfig() {
  MotionGateConfig c;
  c.standing_speed_mps = 0.05;
  c.standing_after_s = 1.0;
  c.timeout_s = 1.0;
  return c;
}

}  // namespace

TEST_CASE(
    "GIVEN a route with a long stop WHEN segmented without and with motion THEN the stop makes a spurious "
    "place only without motion",
    "[segmentation][motion]") {
  const int rooms = 4;
  const std::vector<RouteFrame> steady = route(rooms, 0.3, {});
  const std::vector<RouteFrame> stopped = route(rooms, 0.3, {{7.5, 15.0}, {10.5, 15.0}});
  FiedlerSegmenterConfig with_distance = timeConfig();
  with_distance.window_m = 1.75;

  const Result steady_time = segment(steady, timeConfig(), nullptr);
  const Result stop_time = segment(stopped, timeConfig(), nullptr);
  MotionGate gate(gateConfig());
  const Result stop_motion = segment(stopped, with_distance, &gate);
  WARN("places: steady " << steady_time.places.size() << ", stop without motion " << stop_time.places.size()
                         << ", stop with motion " << stop_motion.places.size() << " (skipped "
                         << stop_motion.skipped << " frames)");
  CHECK(steady_time.places.size() == static_cast<std::size_t>(rooms));
  CHECK(stop_time.places.size() > static_cast<std::size_t>(rooms));
  CHECK(stop_motion.places.size() == static_cast<std::size_t>(rooms));
  CHECK(stop_motion.skipped >= 90);
}

TEST_CASE(
    "GIVEN no motion input WHEN segmented through the motion-aware path THEN the output is bit-identical to "
    "the "
    "time-based segmenter",
    "[segmentation][motion]") {
  const std::vector<RouteFrame> frames = route(4, 0.3, {{7.5, 15.0}, {10.5, 15.0}});
  FiedlerSegmenterConfig with_distance = timeConfig();
  with_distance.window_m = 1.75;
  const Result plain = segment(frames, timeConfig(), nullptr);
  MotionGate silent(gateConfig());
  const Result no_samples = segment(frames, with_distance, &silent, -1.0);  // the gate never hears a sample
  REQUIRE(no_samples.lambda2.size() == plain.lambda2.size());
  for (std::size_t i = 0; i < plain.lambda2.size(); ++i) {
    REQUIRE(no_samples.lambda2[i].has_value() == plain.lambda2[i].has_value());
    if (plain.lambda2[i]) REQUIRE(*no_samples.lambda2[i] == *plain.lambda2[i]);  // exact, not approximate
  }
  REQUIRE(no_samples.places.size() == plain.places.size());
  for (std::size_t i = 0; i < plain.places.size(); ++i) {
    CHECK(no_samples.places[i].first_frame == plain.places[i].first_frame);
    CHECK(no_samples.places[i].last_frame == plain.places[i].last_frame);
    CHECK(no_samples.places[i].representative_frame == plain.places[i].representative_frame);
    CHECK(no_samples.places[i].valley_frame == plain.places[i].valley_frame);
  }
  CHECK(no_samples.skipped == 0);
}

TEST_CASE(
    "GIVEN the motion link is lost mid-route WHEN segmented THEN frames after the loss are segmented by time "
    "and none is skipped",
    "[segmentation][motion]") {
  const std::vector<RouteFrame> frames = route(4, 0.3, {{7.5, 15.0}, {10.5, 15.0}});
  FiedlerSegmenterConfig with_distance = timeConfig();
  with_distance.window_m = 1.75;
  MotionGate gate(gateConfig());
  // The link dies before the stop: the stop is then seen by time only, as without motion.
  const Result lost = segment(frames, with_distance, &gate, 10.0);
  const Result plain = segment(frames, timeConfig(), nullptr);
  CHECK(lost.skipped == 0);
  CHECK_FALSE(gate.at(frames.back().time_s).known);
  CHECK(lost.places.size() == plain.places.size());
}

TEST_CASE(
    "GIVEN three stops of 10 s and a slow stretch at a third of the speed WHEN segmented with the window in "
    "metres THEN the places equal the steady run's",
    "[segmentation][motion]") {
  const int rooms = 4;
  const std::vector<RouteFrame> slow =
      route(rooms, 0.3, {{2.0, 10.0}, {7.5, 10.0}, {10.5, 10.0}}, {13.0, 16.0});
  FiedlerSegmenterConfig with_distance = timeConfig();
  with_distance.window_m = 1.75;
  MotionGate gate(gateConfig());
  const Result motion = segment(slow, with_distance, &gate);
  const Result time_only = segment(slow, timeConfig(), nullptr);
  WARN("three stops and a slow stretch: without motion " << time_only.places.size() << " places, with motion "
                                                         << motion.places.size());
  CHECK(time_only.places.size() > static_cast<std::size_t>(rooms));
  REQUIRE(motion.places.size() == static_cast<std::size_t>(rooms));
  // Each border lies within a metre of a room border.
  for (std::size_t p = 0; p + 1 < motion.places.size(); ++p) {
    const double border_m = slow[static_cast<std::size_t>(motion.places[p + 1].first_frame)].position_m;
    CHECK(std::abs(border_m - kRoomM * static_cast<double>(p + 1)) < 1.0);
  }
}

TEST_CASE("GIVEN window_m out of range WHEN validated THEN the key and range are named",
          "[segmentation][motion]") {
  FiedlerSegmenterConfig c = timeConfig();
  c.window_m = -0.5;
  CHECK(c.validate().find("window_m") == 0);
  c.window_m = 1.75;
  CHECK(c.validate().empty());
}

TEST_CASE(
    "GIVEN a route with a stretch at a third of the speed WHEN segmented with motion and a frame spacing THEN "
    "the slow frames are thinned to the steady density and no frame of the steady route is",
    "[segmentation][motion]") {
  const int rooms = 4;
  // 0.5 m/s at 5 fps: 0.1 m per frame; the slow stretch (8 to 14 m, in room 1 and 2): 0.033 m per frame.
  const std::vector<RouteFrame> steady = route(rooms, 0.5, {});
  const std::vector<RouteFrame> slow = route(rooms, 0.5, {}, {8.0, 14.0});
  FiedlerSegmenterConfig c = timeConfig();
  c.window_m = 3.0;
  c.min_frame_spacing_m = 0.09;
  c.min_frame_spacing_rad = 0.03;
  MotionGate steady_gate(gateConfig()), slow_gate(gateConfig());
  const Result a = segment(steady, c, &steady_gate);
  const Result b = segment(slow, c, &slow_gate);
  CHECK(a.thinned == 0);
  // 6 m at 0.033 m per frame: 180 frames, of which every third is kept.
  CHECK(b.thinned == Approx(120).margin(3));
  CHECK(b.skipped == 0);  // thinned frames are not counted as standing
  // The same places, with borders at the same positions (within one steady frame of travel).
  REQUIRE(a.places.size() == b.places.size());
  for (std::size_t p = 1; p < a.places.size(); ++p) {
    const double xa = steady[static_cast<std::size_t>(a.places[p].first_frame)].position_m;
    const double xb = slow[static_cast<std::size_t>(b.places[p].first_frame)].position_m;
    CHECK(xb == Approx(xa).margin(0.15));
  }
  // Off (0 m): every frame is added.
  c.min_frame_spacing_m = 0.0;
  MotionGate off_gate(gateConfig());
  CHECK(segment(slow, c, &off_gate).thinned == 0);
}

TEST_CASE("GIVEN a robot turning on the spot WHEN its frames are spaced THEN they are kept while the heading changes",
          "[segmentation][motion]") {
  FiedlerSegmenterConfig c = timeConfig();
  c.window_m = 3.0;
  c.min_frame_spacing_m = 0.09;
  c.min_frame_spacing_rad = 0.03;
  const TableSimilarity similarity([](int, int) { return 0.5; });
  FiedlerSegmenter segmenter(c, similarity);
  MotionGate gate(gateConfig());
  // 2 s of turning at 0.5 rad/s without moving (0.1 rad per frame), then 2 s at 0.01 rad/s (0.002 rad).
  for (int i = 0; i < 20; ++i) {
    const double t = 0.2 * i;
    const double rate = i < 10 ? 0.5 : 0.01;
    gate.addSample(t, 0.0, 0.0, rate);
    segmenter.addFrame(i, t, fakeFingerprint(i), gate.at(t));
    if (i == 9) {
      // Turning: every frame is 0.1 rad on from the one before, so none is thinned.
      CHECK(segmenter.thinnedFrames() == 0);
      CHECK(segmenter.windowFrames() == 10);
    }
  }
  // The gate integrates |yaw rate| over each interval: 9 x 0.1 + 10 x 0.002 rad.
  CHECK(gate.at(3.8).turned_rad == Approx(0.92).margin(1e-9));
  // Creeping round from frame 10: less than 0.03 rad per frame from the last frame added, so thinned,
  // until the creep has lasted standing_after_s (1 s from 2.0 s): frames 15-19 stand instead.
  CHECK(segmenter.thinnedFrames() == 5);
  CHECK(segmenter.skippedFrames() == 5);
  CHECK(segmenter.windowFrames() == 10);
}
