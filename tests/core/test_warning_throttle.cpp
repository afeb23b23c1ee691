// WarningThrottle: the first few warnings in full, then summaries "N more suppressed (T in all)" at most once
// per period and at the end, so a folder of thousands of bad files gives a handful of lines and every count.
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "toposlam/core/warning_throttle.hpp"

using toposlam::WarningThrottle;

namespace {

struct Harness {
  std::vector<std::string> lines;
  double now_s = 0.0;
  WarningThrottle::Sink sink() {
    return [this](const std::string& line) { lines.push_back(line); };
  }
  WarningThrottle::Now clock() {
    return [this] { return now_s; };
  }
};

}  // namespace

TEST_CASE("GIVEN 5000 warnings at once WHEN the first 5 pass THEN 5 lines and one final summary of 4995",
          "[core][reliability]") {
  Harness h;
  {
    WarningThrottle throttle("images: skipping bad files", 5, 10.0, h.sink(), h.clock());
    for (int i = 0; i < 5000; ++i) throttle.warn("bad " + std::to_string(i));
    CHECK(throttle.total() == 5000);
    CHECK(throttle.suppressed() == 4995);
    CHECK(throttle.pending() == 4995);
    CHECK(h.lines.size() == 5);
    throttle.flush();
    CHECK(throttle.pending() == 0);
  }  // destroyed: nothing left to summarise
  REQUIRE(h.lines.size() == 6);
  CHECK(h.lines[0] == "bad 0");
  CHECK(h.lines[4] == "bad 4 (images: skipping bad files: further ones are counted and summarised)");
  CHECK(h.lines[5] == "images: skipping bad files: 4995 more suppressed (5000 in all)");
}

TEST_CASE(
    "GIVEN warnings once a second for 35 s WHEN the period is 10 s THEN a summary every 10 s and the rest at "
    "destruction",
    "[core][reliability]") {
  Harness h;
  {
    WarningThrottle throttle("v4l2: skipped buffers", 2, 10.0, h.sink(), h.clock());
    for (int s = 0; s < 35; ++s) {
      h.now_s = s;
      throttle.warn("skip " + std::to_string(s));
    }
  }
  // 2 in full; suppressed from t = 2: summaries at t = 12 (11 warnings, 2..12), t = 23 (13..23), t = 34
  // (24..34).
  REQUIRE(h.lines.size() == 5);
  CHECK(h.lines[2] == "v4l2: skipped buffers: 11 more suppressed (13 in all)");
  CHECK(h.lines[3] == "v4l2: skipped buffers: 11 more suppressed (24 in all)");
  CHECK(h.lines[4] == "v4l2: skipped buffers: 11 more suppressed (35 in all)");
}

TEST_CASE("GIVEN fewer warnings than the first few WHEN flushed THEN no summary line",
          "[core][reliability]") {
  Harness h;
  {
    WarningThrottle throttle("video: skipping frames", 3, 1.0, h.sink(), h.clock());
    throttle.warn("a");
    throttle.warn("b");
    throttle.flush();
  }
  CHECK(h.lines == std::vector<std::string>{"a", "b"});
  CHECK_THROWS_AS(WarningThrottle("x", -1, 1.0, h.sink(), h.clock()), std::invalid_argument);
  CHECK_THROWS_AS(WarningThrottle("x", 1, 0.0, h.sink(), h.clock()), std::invalid_argument);
}
