// FiedlerSegmentationStage when the frames' source clock jumps (docs/reliability.md, "Clock jumps"): a
// window in seconds of a camera at 15 fps, six places of 3 s each; the clock steps back 30 s in the middle
// of the second place (an NTP step on a robot without RTC, played from a recording) or forward an hour.
// The places must be those of the same frames on an honest clock.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "../segmentation/fake_similarity.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"

using toposlam::FiedlerSegmentationStage;
using toposlam::FiedlerSegmenterConfig;
using toposlam::test::fakeFingerprint;
using toposlam::test::TableSimilarity;

namespace {

constexpr int kFramesPerPlace = 45;  // 3 s at 15 fps
constexpr int kFrames = 6 * kFramesPerPlace;
constexpr double kDt = 1.0 / 15.0;

// Six places; inside each, every 6th frame is a poor view (a person walking by: 0.3 to the rest), which
// a window of 2 s (30 frames) rides over and a window of 5 frames does not.
bool poorView(int frame) { return frame % 6 == 3; }
double sixPlaces(int a, int b) {
  if (a / kFramesPerPlace != b / kFramesPerPlace) return 0.05;
  if (a != b && (poorView(a) || poorView(b))) return 0.3;
  return 0.9 + 0.05 * std::sin(0.7 * a + 1.3 * b);
}

FiedlerSegmenterConfig windowInSeconds() {
  FiedlerSegmenterConfig c;
  c.window_s = 2.0;  // 30 frames at 15 fps
  c.window = 40;
  c.min_window_frames = 5;
  return c;
}

using Places = std::vector<std::pair<std::int64_t, std::int64_t>>;

struct Segmented {
  Places places;                ///< closed places: first and last frame
  std::vector<double> lambda2;  ///< per frame (NaN until the window is full)
  std::int64_t steps_back = 0;
};

/// The film with the source times `clock(frame)` through the stage.
Segmented segment(const std::function<double(int)>& clock) {
  const TableSimilarity similarity(sixPlaces);
  FiedlerSegmentationStage stage(windowInSeconds(), similarity);
  Segmented out;
  for (int f = 0; f < kFrames; ++f) {
    // captured_at_s: the pipeline's monotonic clock, which never jumps.
    const auto step = stage.process(f, clock(f), 100.0 + f * kDt, fakeFingerprint(f), cv::Mat());
    out.lambda2.push_back(step.lambda2);
    if (step.closed) out.places.emplace_back(step.closed->first_frame, step.closed->last_frame);
  }
  if (auto last = stage.finish()) out.places.emplace_back(last->first_frame, last->last_frame);
  out.steps_back = stage.sourceTimeStepsBack();
  return out;
}

/// Frames whose lambda2 differs from the honest run's (NaN equals NaN).
int differingFrames(const Segmented& a, const Segmented& b) {
  int differing = 0;
  for (std::size_t f = 0; f < a.lambda2.size(); ++f) {
    const bool both_nan = std::isnan(a.lambda2[f]) && std::isnan(b.lambda2[f]);
    if (!both_nan && !(std::abs(a.lambda2[f] - b.lambda2[f]) <= 1e-9)) ++differing;
  }
  return differing;
}

}  // namespace

TEST_CASE(
    "GIVEN a camera clock stepped back 30 s in the second place WHEN segmenting by seconds THEN every "
    "frame's "
    "window is the one of the honest clock (same lambda2, same places) and the step is counted",
    "[pipeline][reliability][clock]") {
  const Segmented honest = segment([](int f) { return 1000.0 + f * kDt; });
  REQUIRE(honest.places.size() == 6);
  for (std::size_t p = 0; p < honest.places.size(); ++p)  // borders within two frames of 0, 45, 90, ...
    CHECK(std::abs(honest.places[p].first - static_cast<std::int64_t>(p) * kFramesPerPlace) <= 2);
  const Segmented stepped = segment([](int f) { return 1000.0 + f * kDt - (f >= 60 ? 30.0 : 0.0); });
  // Before FrameTimeline, every frame after the step came "1 s after" the one before, for good: a window
  // of min_window_frames (5) frames instead of 30 from frame 60 on (210 of 270 lambda2 values differed).
  CHECK(differingFrames(stepped, honest) == 0);
  CHECK(stepped.places == honest.places);
  CHECK(stepped.steps_back == 1);
}

TEST_CASE(
    "GIVEN a camera clock that steps back twice, by a second and by an hour, WHEN segmenting by seconds THEN "
    "every frame's window is the one of the honest clock",
    "[pipeline][reliability][clock]") {
  const Segmented honest = segment([](int f) { return 1000.0 + f * kDt; });
  const Segmented stepped =
      segment([](int f) { return 5000.0 + f * kDt - (f >= 100 ? 1.0 : 0.0) - (f >= 200 ? 3600.0 : 0.0); });
  CHECK(differingFrames(stepped, honest) == 0);
  CHECK(stepped.places == honest.places);
  CHECK(stepped.steps_back == 2);
}

TEST_CASE(
    "GIVEN a camera clock stepped forward an hour inside a place WHEN segmenting by seconds THEN it is a "
    "gap: "
    "the window restarts there (min_window_frames), and the places stay",
    "[pipeline][reliability][clock]") {
  const Segmented honest = segment([](int f) { return 1000.0 + f * kDt; });
  const Segmented jumped = segment([](int f) { return 1000.0 + f * kDt + (f >= 60 ? 3600.0 : 0.0); });
  CHECK(jumped.steps_back == 0);
  CHECK(jumped.places == honest.places);
  // Only the frames while the window refills differ (it holds 30 frames again 2 s after the jump).
  const int differing = differingFrames(jumped, honest);
  CHECK(differing > 0);
  CHECK(differing <= 30);
}
