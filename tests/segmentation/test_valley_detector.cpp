// Algorithm 4.1 (online valley detection) on hand-made lambda2 series.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "toposlam/segmentation/valley_detector.hpp"

using toposlam::ValleyDetector;
using toposlam::ValleyDetectorConfig;

namespace {

// Feeds values as frames 0, 1, 2, ... and returns every reported valley frame.
std::vector<std::int64_t> valleysOf(const std::vector<double>& series, ValleyDetectorConfig config = {}) {
  ValleyDetector detector(config);
  std::vector<std::int64_t> valleys;
  for (std::size_t i = 0; i < series.size(); ++i) {
    if (auto valley = detector.update(static_cast<std::int64_t>(i), series[i])) valleys.push_back(*valley);
  }
  return valleys;
}

}  // namespace

TEST_CASE(
    "GIVEN a clear peak-valley-peak series WHEN fed to the detector THEN it reports the minimum's frame "
    "once the series has risen delta above it",
    "[segmentation][valley]") {
  // frame:                      0    1    2    3     4    5    6    7    8    9
  const std::vector<double> s = {0.2, 0.6, 0.9, 0.95, 0.6, 0.4, 0.2, 0.3, 0.5, 0.9};
  ValleyDetector detector;
  std::vector<std::optional<std::int64_t>> out;
  for (std::size_t i = 0; i < s.size(); ++i)
    out.push_back(detector.update(static_cast<std::int64_t>(i), s[i]));
  // The peak (0.95) is declared at frame 4 (0.6 < 0.95 - 0.25); the valley (0.2 at frame 6) at frame 8
  // (0.5 > 0.2 + 0.25), not at frame 7 (0.3 is only 0.1 above).
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (i == 8) {
      REQUIRE(out[i].has_value());
      CHECK(*out[i] == 6);
    } else {
      CHECK_FALSE(out[i].has_value());
    }
  }
  CHECK(detector.lookingForPeak());
}

TEST_CASE("GIVEN swings smaller than delta WHEN fed to the detector THEN they are ignored as noise",
          "[segmentation][valley]") {
  SECTION("noise around a high plateau never declares a peak") {
    CHECK(valleysOf({0.9, 0.8, 0.9, 0.75, 0.9, 0.7, 0.9, 0.8}).empty());
  }
  SECTION("noise in a valley does not end it early; the deepest point is reported") {
    // peak 1.0 found at frame 1; min 0.3 at 2; rise to 0.5 (+0.2) is noise; min 0.25 at 4; 0.6 ends it.
    CHECK(valleysOf({1.0, 0.7, 0.3, 0.5, 0.25, 0.45, 0.6}) == std::vector<std::int64_t>{4});
  }
}

TEST_CASE("GIVEN peaks lower than gamma WHEN fed to the detector THEN no valley is declared between them",
          "[segmentation][valley]") {
  CHECK(valleysOf({0.1, 0.45, 0.1, 0.45, 0.1, 0.45, 0.1}).empty());
  SECTION("a later peak above gamma arms it again") {
    // frames 0..6 low peaks; 0.8 at 7 is a peak (>= 0.5), 0.4 at 8 confirms it, 0.8 at 9 the valley at 8.
    CHECK(valleysOf({0.1, 0.45, 0.1, 0.45, 0.1, 0.45, 0.1, 0.8, 0.4, 0.8}) == std::vector<std::int64_t>{8});
  }
  SECTION("with gamma lowered to 0.4 the same low peaks count") {
    CHECK(valleysOf({0.1, 0.45, 0.1, 0.45, 0.1}, {0.4, 0.25}) == std::vector<std::int64_t>{2});
  }
}

TEST_CASE(
    "GIVEN the valley minimum is the value that confirmed the peak WHEN the valley is declared THEN its "
    "own frame is reported (fixes the pseudo-code's stale minIdx)",
    "[segmentation][valley]") {
  // 0.1 at frame 1 is an early minimum; the peak (1.0) is confirmed by 0.7 at frame 3, which is also the
  // valley's minimum. The thesis' pseudo-code would return the stale frame 1.
  CHECK(valleysOf({0.2, 0.1, 1.0, 0.7, 0.96}) == std::vector<std::int64_t>{3});
}

TEST_CASE("GIVEN a long series with two valleys WHEN fed THEN both are reported in order",
          "[segmentation][valley]") {
  CHECK(valleysOf({1.0, 0.5, 0.2, 0.9, 1.0, 0.6, 0.3, 0.1, 0.2, 1.0}) == std::vector<std::int64_t>{2, 7});
}

TEST_CASE("GIVEN non-finite values WHEN fed THEN they change nothing", "[segmentation][valley]") {
  CHECK(valleysOf({1.0, NAN, 0.6, INFINITY, 0.2, 0.9}) == std::vector<std::int64_t>{4});
}

TEST_CASE("GIVEN an invalid config WHEN a detector is built THEN the message names the key and range",
          "[segmentation][valley]") {
  CHECK(ValleyDetectorConfig{0.5, 0.25}.validate().empty());
  CHECK(ValleyDetectorConfig{-0.1, 0.0}.validate().rfind("gamma:", 0) == 0);
  CHECK(ValleyDetectorConfig{1.2, 0.1}.validate(1.0417).rfind("gamma:", 0) == 0);
  CHECK(ValleyDetectorConfig{0.5, 0.6}.validate().rfind("delta:", 0) == 0);
  CHECK_THROWS_WITH(ValleyDetector(ValleyDetectorConfig{0.5, 0.6}), Catch::Contains("delta"));
}
