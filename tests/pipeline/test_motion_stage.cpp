// FiedlerSegmentationStage with motion (docs/segmentation.md, "Motion-aware segmentation"): without samples
// it is the plain segmenter; samples from another thread make standing frames skipped; a silent link
// falls back; the sample queue is bounded.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <string>
#include <thread>

#include "../segmentation/fake_similarity.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"

using toposlam::FiedlerSegmentationStage;
using toposlam::FiedlerSegmenter;
using toposlam::FiedlerSegmenterConfig;
using toposlam::MotionGateConfig;
using toposlam::MotionSample;
using toposlam::test::fakeFingerprint;
using toposlam::test::TableSimilarity;

namespace {
// Three blocks of 40 near-identical frames.
double blocks(int a, int b) { return a / 40 == b / 40 ? 0.9 + 0.05 * std::sin(0.7 * a + 1.3 * b) : 0.05; }
FiedlerSegmenterConfig stageConfig() {
  FiedlerSegmenterConfig c;
  c.window = 20;
  c.window_m = 1.5;
  return c;
}
}  // namespace

TEST_CASE(
    "GIVEN no motion sample WHEN frames go through the stage THEN lambda2 equals the plain segmenter's "
    "exactly",
    "[pipeline][motion]") {
  const TableSimilarity similarity(blocks);
  FiedlerSegmentationStage stage(stageConfig(), similarity);
  FiedlerSegmenter plain(stageConfig(), similarity);
  int closed = 0, plain_closed = 0;
  for (int f = 0; f < 120; ++f) {
    const auto step = stage.process(f, static_cast<double>(f), 100.0 + 0.2 * f, fakeFingerprint(f), cv::Mat());
    const auto expected = plain.addFrame(f, static_cast<double>(f), fakeFingerprint(f));
    REQUIRE(std::isnan(step.lambda2) == !expected.lambda2.has_value());
    if (expected.lambda2) REQUIRE(step.lambda2 == *expected.lambda2);
    closed += step.closed ? 1 : 0;
    plain_closed += expected.closed_place ? 1 : 0;
  }
  CHECK(closed == plain_closed);
  CHECK(stage.skippedFrames() == 0);
  CHECK_FALSE(stage.lastMotion().known);
}

TEST_CASE(
    "GIVEN motion samples from another thread saying the robot stands WHEN frames arrive THEN they are "
    "skipped, and "
    "once the samples stop, motion is unknown and frames are added again",
    "[pipeline][motion]") {
  const TableSimilarity similarity(blocks);
  MotionGateConfig gate;
  gate.standing_after_s = 1.0;
  gate.timeout_s = 0.5;
  FiedlerSegmentationStage stage(stageConfig(), similarity, 600, gate);
  toposlam::MotionStatusCounters counters;
  {
    FiedlerSegmentationStage fresh(stageConfig(), similarity, 600, gate);
    fresh.reportMotionTo(&counters);
    fresh.process(0, 99.0, 99.0, fakeFingerprint(0), cv::Mat());  // no sample yet
    CHECK(counters.use.load() == static_cast<int>(toposlam::MotionUse::None));
  }
  stage.reportMotionTo(&counters);
  std::thread feeder([&stage] {
    for (int i = 0; i <= 50; ++i) stage.addMotion(MotionSample{100.0 + 0.1 * i, 0.0, 0.0});  // 100 .. 105 s
  });
  feeder.join();
  for (int f = 0; f < 30; ++f) {
    const double t = 100.0 + 0.2 * f;  // 100 .. 105.8 s
    const auto step = stage.process(f, t, t, fakeFingerprint(f), cv::Mat());
    if (t >= 101.0 && t <= 105.5) {
      CHECK(stage.lastMotion().standing);
      CHECK(std::isnan(step.lambda2));
      CHECK(counters.use.load() == static_cast<int>(toposlam::MotionUse::Used));
      CHECK(counters.standing_frames.load() == stage.skippedFrames());
    }
  }
  // The status message's view: the link went silent, 23 frames were left out.
  CHECK(counters.use.load() == static_cast<int>(toposlam::MotionUse::Lost));
  CHECK(counters.standing_frames.load() == 23);
  CHECK(std::string(toposlam::toString(toposlam::MotionUse::Lost)) == "lost");
  CHECK(stage.skippedFrames() == 23);     // frames 5 .. 27 (101.0 .. 105.4 s)
  CHECK_FALSE(stage.lastMotion().known);  // 105.8 s: the newest sample is 0.8 s old
  CHECK(stage.refusedMotionSamples() == 0);
  stage.addMotion(MotionSample{50.0, 0.0, 0.0});  // back in time: refused by the gate
  stage.process(30, 106.0, 106.0, fakeFingerprint(30), cv::Mat());
  CHECK(stage.refusedMotionSamples() == 1);
}

TEST_CASE(
    "GIVEN more samples than the queue holds before a frame WHEN added THEN the oldest are dropped and "
    "counted",
    "[pipeline][motion]") {
  const TableSimilarity similarity(blocks);
  FiedlerSegmentationStage stage(stageConfig(), similarity);
  const auto n = static_cast<int>(FiedlerSegmentationStage::kMaxPendingMotion) + 10;
  for (int i = 0; i < n; ++i) stage.addMotion(MotionSample{0.01 * i, 0.001, 0.1});
  CHECK(stage.droppedMotionSamples() == 10);
  stage.process(0, 0.0, 0.01 * n, fakeFingerprint(0), cv::Mat());
  CHECK(stage.lastMotion().known);
  CHECK(stage.lastMotion().distance_m ==
        Approx(0.001 * static_cast<double>(FiedlerSegmentationStage::kMaxPendingMotion)));
}

TEST_CASE("GIVEN motion samples stamped by another clock WHEN frames arrive THEN every sample is refused, the status "
          "says stale and counts them, and samples on the right clock are used again at once",
          "[pipeline][motion]") {
  const TableSimilarity similarity(blocks);
  FiedlerSegmentationStage stage(stageConfig(), similarity);  // default gate: clock_tolerance_s 1 s
  toposlam::MotionStatusCounters counters;
  stage.reportMotionTo(&counters);
  // Frames on the pipeline clock from 100 s; the robot stands. For 2 s the samples carry Unix time.
  for (int frame = 0; frame < 20; ++frame) {  // 100.0 .. 101.9 s
    const double t = 100.0 + 0.1 * frame;
    stage.addMotion(MotionSample{1.7e9 + t, 0.0, 0.0, 0.0, t});
    stage.process(frame, t, t, fakeFingerprint(frame), cv::Mat());
  }
  CHECK(stage.refusedMotionSamples() == 20);
  CHECK(stage.motionRefusals().off_clock == 20);
  CHECK(stage.motionSamples() == 0);
  CHECK(counters.use.load() == static_cast<int>(toposlam::MotionUse::Stale));
  CHECK(counters.refused.load() == 20);
  CHECK(toposlam::motionStatusText(counters) ==
        "motion stale (segmenting by time), 0 standing frames skipped, motion refused 20");
  CHECK(stage.skippedFrames() == 0);
  // The sender fixed: its samples are used, and the stop is seen once it has lasted standing_after_s.
  for (int frame = 20; frame < 40; ++frame) {  // 102.0 .. 103.9 s
    const double t = 100.0 + 0.1 * frame;
    stage.addMotion(MotionSample{t, 0.0, 0.0, 0.0, t});
    stage.process(frame, t, t, fakeFingerprint(frame), cv::Mat());
  }
  CHECK(counters.use.load() == static_cast<int>(toposlam::MotionUse::Used));
  CHECK(stage.skippedFrames() == 10);  // 103.0 .. 103.9 s
  CHECK(toposlam::motionStatusText(counters) == "motion used, 10 standing frames skipped, motion refused 20");
  CHECK(toposlam::motionStatusText("none", 0, 0, 0, 0).empty());
  CHECK(toposlam::motionStatusText("none", 0, 0, 0, -1).empty());  // fragments not counted: nothing to say
  CHECK(toposlam::motionStatusText("lost", 3, 0, 0, 0) ==
        "motion lost (segmenting by time), 3 standing frames skipped");
  // Messages that could not be decoded, or were lost in reassembly, are said even before any sample was used.
  CHECK(toposlam::motionStatusText("none", 0, 0, 2, 0) ==
        "motion none, 0 standing frames skipped, motion malformed 2");
  CHECK(toposlam::motionStatusText("none", 0, 0, 2, 3) ==
        "motion none, 0 standing frames skipped, motion malformed 2, motion fragments abandoned 3");
}
