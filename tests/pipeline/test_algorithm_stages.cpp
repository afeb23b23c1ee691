// The stage adapters of src/pipeline/algorithm_stages.cpp, each alone: VpackFingerprintStage (the
// fingerprint is the extractor's; the place-event thumbnail is made here, from the frame it was given).
#include <catch2/catch.hpp>

#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"

using namespace toposlam;

namespace {

/// A 320x240 BGR frame of vertical stripes (the extractor finds edges and keypoints in it) whose columns
/// alternate between two values, so that halving its width by pixel-area averaging gives their mean.
cv::Mat stripedFrame() {
  cv::Mat frame(240, 320, CV_8UC3);
  for (int x = 0; x < frame.cols; ++x) {
    const bool dark_stripe = (x / 40) % 2 == 1;
    const int base = dark_stripe ? 20 : 180;
    const cv::Scalar colour(base + (x % 2) * 40, base / 2 + (x % 2) * 20, 90 + (x % 2) * 60);
    frame.col(x).setTo(colour);
  }
  // Corners for the keypoint detector.
  for (int y = 20; y < 220; y += 50)
    for (int x = 10; x < 310; x += 60)
      cv::rectangle(frame, cv::Rect(x, y, 12, 12), cv::Scalar(255, 255, 255), cv::FILLED);
  return frame;
}

}  // namespace

TEST_CASE("GIVEN a 320x240 frame WHEN the fingerprint stage makes a 160-pixel thumbnail THEN it is 160x120, "
          "pixel-area averaged, and the fingerprint is the extractor's",
          "[pipeline][stages][thumbnail]") {
  const cv::Mat frame = stripedFrame();
  VpackFingerprintStage stage(VpackConfig{}, nullptr, 160);
  const FingerprintedFrame out = stage.process(frame, cv::Mat());

  REQUIRE(out.thumbnail.cols == 160);
  REQUIRE(out.thumbnail.rows == 120);
  REQUIRE(out.thumbnail.type() == CV_8UC3);
  // Column pairs (2k, 2k+1) of a bright stripe are (180, 90, 90) and (220, 110, 150): their mean.
  CHECK(out.thumbnail.at<cv::Vec3b>(0, 0) == cv::Vec3b(200, 100, 120));
  // Of a dark stripe (x 40..79 -> thumbnail 20..39): (20, 10, 90) and (60, 30, 150).
  CHECK(out.thumbnail.at<cv::Vec3b>(0, 25) == cv::Vec3b(40, 20, 120));
  cv::Mat expected;
  cv::resize(frame, expected, cv::Size(160, 120), 0, 0, cv::INTER_AREA);
  CHECK(cv::norm(out.thumbnail, expected, cv::NORM_INF) == 0.0);
  // The thumbnail is a copy: the frame's buffer may go back to the source.
  CHECK(out.thumbnail.data != frame.data);

  const Fingerprint alone = VpackExtractor(VpackConfig{}).extract(frame);
  CHECK(alone.keypointCount() > 0);
  CHECK(alone.edge_columns.size() >= 4);
  CHECK(out.fingerprint.equals(alone));
}

TEST_CASE("GIVEN frames of other sizes WHEN thumbnails are made THEN the height keeps the aspect (at "
          "least 1) and a frame narrower than the width is not enlarged",
          "[pipeline][stages][thumbnail]") {
  VpackFingerprintStage stage(VpackConfig{}, nullptr, 160);
  cv::Mat frame333;
  cv::resize(stripedFrame(), frame333, cv::Size(333, 100));
  const FingerprintedFrame a = stage.process(frame333, cv::Mat());
  CHECK(a.thumbnail.cols == 160);
  CHECK(a.thumbnail.rows == 48);  // 100 * 160 / 333 = 48.05

  cv::Mat small;
  cv::resize(stripedFrame(), small, cv::Size(64, 48), 0, 0, cv::INTER_AREA);
  const FingerprintedFrame b = stage.process(small, cv::Mat());
  REQUIRE(b.thumbnail.size() == cv::Size(64, 48));
  CHECK(cv::norm(b.thumbnail, small, cv::NORM_INF) == 0.0);

  VpackFingerprintStage narrow(VpackConfig{}, nullptr, 16);
  cv::Mat strip;
  cv::resize(stripedFrame(), strip, cv::Size(1000, 16));
  const FingerprintedFrame c = narrow.process(strip, cv::Mat());
  CHECK(c.thumbnail.size() == cv::Size(16, 1));  // 16 * 16 / 1000 rounds to 0: one row
}

TEST_CASE("GIVEN a grey camera frame WHEN the thumbnail is made THEN it is grey too",
          "[pipeline][stages][thumbnail]") {
  cv::Mat grey;
  cv::cvtColor(stripedFrame(), grey, cv::COLOR_BGR2GRAY);
  VpackFingerprintStage stage(VpackConfig{}, nullptr, 80);
  const FingerprintedFrame out = stage.process(grey, grey);
  REQUIRE(out.thumbnail.type() == CV_8UC1);
  CHECK(out.thumbnail.size() == cv::Size(80, 60));
}

TEST_CASE("GIVEN the offline commands' stage (no thumbnail) WHEN a frame is processed THEN the thumbnail is "
          "empty and the fingerprint the same",
          "[pipeline][stages][thumbnail]") {
  const cv::Mat frame = stripedFrame();
  VpackFingerprintStage offline(VpackConfig{}, nullptr);
  VpackFingerprintStage daemon(VpackConfig{}, nullptr, 160);
  const FingerprintedFrame a = offline.process(frame, cv::Mat());
  CHECK(a.thumbnail.empty());
  CHECK(a.fingerprint.equals(daemon.process(frame, cv::Mat()).fingerprint));
}
