// Frame-level loop closures by sequence evidence: hand-computed steps of the detector, whole runs with
// tagged fingerprints (one lap, then the same lap again), keyframes at a camera rate, bad input.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "fake_similarity.hpp"
#include "toposlam/topology/sequence_loop_closures.hpp"

using namespace toposlam;
using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;

namespace {

/// Same tag 0.8, adjacent tags 0.3, otherwise 0.1 plus a fixed pseudo-random part in [0, 0.05).
test::TagSimilarity lapSimilarity() {
  return test::TagSimilarity([](int a, int b) {
    if (a == b) return 0.8;
    if (std::abs(a - b) == 1) return 0.3;
    const auto h = static_cast<std::uint32_t>(a * 7919 + b * 104729) * 2654435761u;
    return 0.1 + 0.05 * static_cast<double>(h >> 8) / static_cast<double>(1u << 24);
  });
}

}  // namespace

TEST_CASE("sequence loop detector: three steps computed by hand", "[sequence_loops]") {
  SequenceLoopConfig config;
  config.decay = 0.5;
  config.min_gap_keyframes = 1;
  SequenceLoopDetector detector(config);
  CHECK(detector.add({}).keyframe == -1);
  // One earlier keyframe: no spread to judge by, z = 0, no detection.
  CHECK(detector.add({0.3}).keyframe == -1);
  // mean 0.4, std 0.2: z = (-1, 1); D = 0.5 z + 0.5 D(previous, g - 1) = (-0.5, 0.5).
  const SequenceLoopDetector::Detection third = detector.add({0.2, 0.6});
  CHECK(third.keyframe == 1);
  CHECK_THAT(third.score, WithinAbs(0.5, 1e-12));
  // mean 0.3, std sqrt(0.08): z = (-0.7071, -0.7071, 1.4142); D(3, 2) = 0.5 * 1.4142 + 0.5 * D(2, 1) = 0.9571.
  const SequenceLoopDetector::Detection fourth = detector.add({0.1, 0.1, 0.7});
  CHECK(fourth.keyframe == 2);
  CHECK_THAT(fourth.score, WithinAbs(0.5 * 0.2 / std::sqrt(0.08) * 2.0 + 0.25, 1e-9));
  CHECK(detector.keyframes() == 4);
}

TEST_CASE("sequence loop detector: no diagonal runs across the start of a traversal", "[sequence_loops]") {
  SequenceLoopConfig config;
  config.decay = 0.5;
  config.min_gap_keyframes = 1;
  // As in the hand-computed case (where D(3, 2) = 0.9571 carries D(2, 1) = 0.5), but keyframe 2 began a
  // traversal: D(3, 2) is its own evidence only.
  SequenceLoopDetector split(config);
  split.add({});
  split.add({0.3});
  split.add({0.2, 0.6}, false);
  const SequenceLoopDetector::Detection d = split.add({0.1, 0.1, 0.7});
  CHECK(d.keyframe == 2);
  CHECK_THAT(d.score, WithinAbs(0.5 * 0.4 / std::sqrt(0.08), 1e-9));
}

TEST_CASE("sequence loop detector: the minimum gap keeps recent keyframes out", "[sequence_loops]") {
  SequenceLoopConfig config;
  config.decay = 0.0;
  config.min_gap_keyframes = 2;
  SequenceLoopDetector detector(config);
  detector.add({});
  detector.add({0.5});
  // The newest earlier keyframe (g = 1, one back) stands out but is too recent; g = 0 is below the mean.
  CHECK(detector.add({0.1, 0.9}).keyframe == -1);
  // g = 0 is three back and stands out: detected.
  const auto d = detector.add({0.9, 0.1, 0.1});
  CHECK(d.keyframe == 0);
  CHECK(d.score > 1.0);
}

TEST_CASE("sequence loop closures: a second lap finds the first, the first lap finds nothing above it",
          "[sequence_loops]") {
  const int lap = 40;
  std::vector<double> time_s;
  std::vector<std::shared_ptr<const Fingerprint>> fingerprints;
  for (int traversal = 0; traversal < 2; ++traversal) {
    for (int i = 0; i < lap; ++i) {
      time_s.push_back(static_cast<double>(i));  // each traversal starts its clock at 0
      fingerprints.push_back(test::taggedFingerprint(i));
    }
  }
  const test::TagSimilarity similarity = lapSimilarity();
  SequenceLoopConfig config;
  config.min_gap_keyframes = 20;
  config.decay = 0.9;
  const std::vector<FrameMatch> matches = matchFramesBySequence(time_s, fingerprints, similarity, config);
  REQUIRE(matches.size() == 2u * lap);
  double first_lap_max = 0.0;
  for (int f = 0; f < lap; ++f) first_lap_max = std::max(first_lap_max, matches[static_cast<std::size_t>(f)].score);
  double second_lap_min = std::numeric_limits<double>::infinity();
  int right = 0;
  for (int f = lap; f < 2 * lap; ++f) {
    const FrameMatch& m = matches[static_cast<std::size_t>(f)];
    if (m.match_frame == f - lap) ++right;
    if (f >= lap + 5) second_lap_min = std::min(second_lap_min, m.score);
  }
  CHECK(right == lap);  // every second-lap frame, from its first, on its first-lap twin
  // After five frames of the revisit its evidence is above anything the first lap ever scored, so recall
  // at 100 % precision is at least (lap - 5) / lap.
  CHECK(second_lap_min > first_lap_max);
  CHECK(first_lap_max < 0.5);
}

TEST_CASE("sequence loop closures: keyframes once a second, the frames between matched around them",
          "[sequence_loops]") {
  // 5 frames per second, 150 frames a lap (30 s), every frame its own tag; the second lap retraces it.
  const int lap = 150;
  std::vector<double> time_s;
  std::vector<std::shared_ptr<const Fingerprint>> fingerprints;
  for (int traversal = 0; traversal < 2; ++traversal) {
    for (int i = 0; i < lap; ++i) {
      time_s.push_back(0.2 * i + 100.0 * traversal);
      fingerprints.push_back(test::taggedFingerprint(i));
    }
  }
  fingerprints[7] = nullptr;  // a frame without a fingerprint is never a keyframe nor a candidate
  const test::TagSimilarity similarity = lapSimilarity();
  const long before = similarity.calls();
  SequenceLoopConfig config;  // defaults: 1 s keyframes, decay 0.95, 20 keyframes back
  const std::vector<FrameMatch> matches = matchFramesBySequence(time_s, fingerprints, similarity, config);
  // 60 keyframes: 59 * 60 / 2 pairs (twice: symmetric), plus at most 5 candidates for each frame.
  CHECK(similarity.calls() - before <= 2 * (59 * 60 / 2 + 5L * 2 * lap));
  int right = 0;
  for (int f = lap; f < 2 * lap; ++f) right += matches[static_cast<std::size_t>(f)].match_frame == f - lap ? 1 : 0;
  CHECK(right >= lap - 2);  // frame 7's twin has no fingerprint: it matches a neighbour
  CHECK(matches[static_cast<std::size_t>(lap + 7)].match_frame != 7);
  for (int f = 0; f < 2 * lap; ++f) CHECK(matches[static_cast<std::size_t>(f)].match_frame < f);
}

TEST_CASE("sequence loop closures: bad settings and input are refused, naming what is wrong", "[sequence_loops]") {
  SequenceLoopConfig config;
  config.decay = 1.0;
  CHECK_THAT(config.validate(), Contains("decay"));
  config = {};
  config.min_gap_keyframes = 0;
  CHECK_THAT(config.validate(), Contains("gap"));
  config = {};
  config.keyframe_interval_s = std::numeric_limits<double>::quiet_NaN();
  CHECK_THAT(config.validate(), Contains("keyframe interval"));
  config = {};
  config.sigma_floor = 0.0;
  CHECK_THAT(config.validate(), Contains("sigma floor"));
  CHECK_THROWS_AS(SequenceLoopDetector(config), std::invalid_argument);

  SequenceLoopDetector detector{SequenceLoopConfig{}};
  detector.add({});
  CHECK_THROWS_WITH(detector.add({0.1, 0.2}), Contains("2 similarities for 1 earlier keyframes"));
  const test::TagSimilarity similarity = lapSimilarity();
  CHECK_THROWS_AS(matchFramesBySequence({0.0, 1.0}, {test::taggedFingerprint(0)}, similarity, SequenceLoopConfig{}),
                  std::invalid_argument);
}
