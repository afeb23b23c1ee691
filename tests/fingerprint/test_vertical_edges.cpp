// Vertical edge detection (thesis 3.2.1) and the 1-D NMS of Algorithm 3.1.
#include <algorithm>
#include <cmath>
#include <random>

#include <catch2/catch.hpp>
#include <opencv2/imgproc.hpp>

#include "test_helpers.hpp"
#include "toposlam/fingerprint/vertical_edge_detector.hpp"

using namespace toposlam;

namespace {

cv::Mat grey(const cv::Mat& bgr) {
  cv::Mat g;
  cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
  return g;
}

// A bar of width w at column c has two intensity steps, at c and c + w; with w <= the NMS
// neighbourhood only one edge survives, which must lie within the bar's borders (+-2 px).
bool nearAny(int column, const std::vector<int>& expected, int tolerance) {
  for (int e : expected)
    if (std::abs(column - e) <= tolerance) return true;
  return false;
}

// Reference: i is a maximum iff h[i] > 0 and h[i] > every other value within n of it.
std::vector<int> bruteForceMaxima(const std::vector<float>& h, int n) {
  std::vector<int> out;
  const int length = static_cast<int>(h.size());
  for (int i = 0; i < length; ++i) {
    if (h[i] <= 0.f) continue;
    bool is_max = true;
    for (int m = std::max(0, i - n); m <= std::min(length - 1, i + n) && is_max; ++m)
      if (m != i && h[m] >= h[i]) is_max = false;
    if (is_max) out.push_back(i);
  }
  return out;
}

}  // namespace

TEST_CASE("GIVEN bars at known columns WHEN edges are detected THEN one edge per bar within 2 px") {
  const std::vector<int> bars = {60, 150, 260, 400, 530};
  const cv::Mat image = test::barsFrame(640, 480, bars, 6);
  const VerticalEdges edges = VerticalEdgeDetector().detect(grey(image));
  REQUIRE(edges.columns.size() == bars.size());
  for (std::size_t i = 0; i < bars.size(); ++i) {
    CHECK(edges.columns[i] >= bars[i] - 2);
    CHECK(edges.columns[i] <= bars[i] + 6 + 2);
  }
}

TEST_CASE("GIVEN wide panels WHEN edges are detected THEN both borders of each panel are found") {
  // Two 100-px dark panels: four steps, each far from the others.
  const cv::Mat image = test::barsFrame(640, 480, {100, 400}, 100);
  const VerticalEdges edges = VerticalEdgeDetector().detect(grey(image));
  const std::vector<int> steps = {100, 200, 400, 500};
  REQUIRE(edges.columns.size() == steps.size());
  for (int c : edges.columns) CHECK(nearAny(c, steps, 2));
}

TEST_CASE("GIVEN vertical segments shorter than H/5 WHEN edges are detected THEN they are ignored") {
  const int height = 480;
  // Segments of 80 px (< 96 = H/5) at 100 and 300; a full-height bar at 500 makes the mean meaningful.
  cv::Mat image = test::barsFrame(640, height, {100, 300}, 6, 80);
  image(cv::Rect(500, 0, 6, height)).setTo(cv::Scalar(40, 40, 40));
  const VerticalEdges edges = VerticalEdgeDetector().detect(grey(image));
  REQUIRE(edges.columns.size() == 1);
  CHECK(nearAny(edges.columns[0], {500, 506}, 2));
  // and segments of 120 px (> H/5) are kept
  cv::Mat tall = test::barsFrame(640, height, {100, 300}, 6, 120);
  CHECK(VerticalEdgeDetector().detect(grey(tall)).columns.size() == 2);
}

TEST_CASE("GIVEN a frame with no structure WHEN edges are detected THEN there are none") {
  cv::Mat flat(240, 320, CV_8UC1, cv::Scalar(128));
  CHECK(VerticalEdgeDetector().detect(flat).columns.empty());
  // Horizontal stripes have no vertical edges either.
  cv::Mat stripes(240, 320, CV_8UC1, cv::Scalar(128));
  for (int y = 0; y < 240; y += 20) stripes.row(y).setTo(cv::Scalar(0));
  CHECK(VerticalEdgeDetector().detect(stripes).columns.empty());
}

TEST_CASE("GIVEN two edges closer than 5 % of the width WHEN edges are detected THEN one remains") {
  // 640 px wide: minimum separation 32 px. Bars at 300 and 320 (20 px apart) -> one edge.
  const cv::Mat image = test::barsFrame(640, 480, {300, 320, 100}, 3);
  const VerticalEdges edges = VerticalEdgeDetector().detect(grey(image));
  REQUIRE(edges.columns.size() == 2);
  CHECK(nearAny(edges.columns[0], {100, 103}, 2));
  CHECK(nearAny(edges.columns[1], {300, 303, 320, 323}, 2));
  // ... while bars 60 px apart stay two edges.
  const cv::Mat apart = test::barsFrame(640, 480, {300, 360, 100}, 3);
  CHECK(VerticalEdgeDetector().detect(grey(apart)).columns.size() == 3);
}

TEST_CASE("GIVEN random sequences WHEN the NMS of Algorithm 3.1 runs THEN it equals the brute-force maxima") {
  std::mt19937_64 rng(20141121);
  std::uniform_real_distribution<float> value(0.f, 1.f);
  std::uniform_int_distribution<int> length_dist(1, 300);
  std::uniform_int_distribution<int> n_dist(1, 40);
  std::bernoulli_distribution zero(0.5);
  for (int trial = 0; trial < 3000; ++trial) {
    const int length = length_dist(rng);
    const int n = n_dist(rng);
    std::vector<float> h(length);
    // Distinct positive values (ties have no single right answer), with about half zeroed as the
    // threshold does, so the plateaus of zeros are exercised too.
    for (float& v : h) v = zero(rng) ? 0.f : value(rng) + 1e-6f;
    INFO("trial " << trial << " length " << length << " n " << n);
    REQUIRE(nonMaximumSuppression1d(h, n) == bruteForceMaxima(h, n));
  }
}

TEST_CASE("GIVEN maxima at both ends WHEN the NMS runs THEN they count (the thesis' border adaptation)") {
  const std::vector<float> h = {9, 1, 2, 3, 2, 1, 0.5, 1, 2, 8};
  CHECK(nonMaximumSuppression1d(h, 3) == std::vector<int>{0, 9});
  CHECK(nonMaximumSuppression1d({5}, 2) == std::vector<int>{0});
  CHECK(nonMaximumSuppression1d({}, 2).empty());
}

TEST_CASE("GIVEN bad edge configs WHEN validated THEN the key is named") {
  VerticalEdgeConfig c;
  c.min_separation_fraction = 0.9;
  CHECK_THAT(c.validate(), Catch::Contains("min_separation_fraction"));
  CHECK_THROWS_WITH(VerticalEdgeDetector(c), Catch::Contains("min_separation_fraction"));
  VerticalEdgeConfig d;
  d.opening_height_fraction = 0;
  CHECK_THAT(d.validate(), Catch::Contains("opening_height_fraction"));
}

namespace {

// Steps 1-4 as OpenCV's filters compute them (the detector's code before issue 18), normalised.
std::vector<float> openCvColumnResponse(const cv::Mat& grey, const toposlam::VerticalEdgeConfig& config) {
  cv::Mat gradient, magnitude, dilated, opened, sums;
  cv::Sobel(grey, gradient, CV_16S, 1, 0, 3);
  cv::convertScaleAbs(gradient, magnitude);
  cv::dilate(magnitude, dilated,
             cv::getStructuringElement(cv::MORPH_RECT, cv::Size(config.dilation_width, 1)));
  const int opening =
      std::clamp(static_cast<int>(std::lround(config.opening_height_fraction * grey.rows)), 1, grey.rows);
  cv::morphologyEx(dilated, opened, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(1, opening)));
  cv::reduce(opened, sums, 0, cv::REDUCE_SUM, CV_32F);
  std::vector<float> response(sums.ptr<float>(0), sums.ptr<float>(0) + grey.cols);
  float peak = 0.f;
  for (float v : response) peak = std::max(peak, v);
  if (peak <= 0.f) return response;
  for (float& v : response) v /= peak;
  return response;
}

}  // namespace

TEST_CASE(
    "GIVEN images of any size and edge configs WHEN the column response is computed THEN it equals "
    "OpenCV's Sobel, dilation, opening and column sum to the bit") {
  std::mt19937 rng(18);
  std::vector<cv::Mat> images;
  for (cv::Size size : {cv::Size(1, 1), cv::Size(2, 2), cv::Size(3, 5), cv::Size(17, 16), cv::Size(64, 7),
                        cv::Size(101, 99)}) {
    cv::Mat noise(size, CV_8UC1);
    cv::randu(noise, 0, 256);
    images.push_back(noise);
    cv::Mat bars(size, CV_8UC1, cv::Scalar(200));  // long vertical structure, and short pieces
    for (int x = 1; x < size.width; x += 7) bars.col(x).setTo(20);
    for (int y = 0; y < size.height; y += 5) bars(cv::Rect(0, y, size.width, 1)).setTo(90);
    images.push_back(bars);
  }
  for (int i : {1, 44, 84}) {
    cv::Mat grey;
    cv::cvtColor(toposlam::test::sampleFrame(i), grey, cv::COLOR_BGR2GRAY);
    images.push_back(grey);
    // Views: neighbours beyond the view come from the frame; one view reaches the frame's own border.
    images.push_back(grey(cv::Rect(13, 7, 301, 250)));
    images.push_back(grey(cv::Rect(grey.cols - 120, grey.rows - 90, 120, 90)));
  }
  for (int width : {1, 2, 3, 4, 7}) {
    for (double fraction : {0.01, 0.2, 0.37, 1.0}) {
      toposlam::VerticalEdgeConfig config;
      config.dilation_width = width;
      config.opening_height_fraction = fraction;
      const toposlam::VerticalEdgeDetector detector(config);
      toposlam::VerticalEdgeScratch scratch;  // shared by every image: sizes change under it
      toposlam::VerticalEdges edges;
      for (const cv::Mat& image : images) {
        INFO(image.cols << "x" << image.rows << ", dilation " << width << ", opening " << fraction);
        detector.detect(image, edges, scratch);
        CHECK(edges.column_response == openCvColumnResponse(image, config));
      }
    }
  }
}
