// The 13-bin HCL histogram with fuzzy voting (thesis 3.2.2).
#include <numeric>
#include <random>

#include <opencv2/imgproc.hpp>

#include <catch2/catch.hpp>

#include "toposlam/fingerprint/hcl_histogram.hpp"

using namespace toposlam;
using Catch::Detail::Approx;

namespace {

HclHistogramBins patch(int r, int g, int b) {
  cv::Mat image(20, 30, CV_8UC3, cv::Scalar(b, g, r));
  return HclHistogram().compute(image, 0, image.cols);
}

float sum(const HclHistogramBins& h) { return std::accumulate(h.begin(), h.end(), 0.f); }

constexpr int kWhite = 8, kLight = 9, kMedium = 10, kDark = 11, kBlack = 12;

}  // namespace

TEST_CASE("GIVEN pure-hue patches WHEN histogrammed THEN the mass sits in the expected hue bins") {
  SECTION("red (hue 0) is entirely in bin 0") {
    const auto h = patch(255, 0, 0);
    CHECK(h[0] == Approx(1.0));
  }
  SECTION("green (hue 120 deg = level 85.3) splits between bins 2 (90 deg) and 3 (135 deg)") {
    const auto h = patch(0, 255, 0);
    CHECK(h[2] == Approx(1.0 - 21.0 / 32).margin(1e-6));
    CHECK(h[3] == Approx(21.0 / 32).margin(1e-6));
  }
  SECTION("blue (hue 240 deg = level 170.7) splits between bins 5 and 6") {
    const auto h = patch(0, 0, 255);
    CHECK(h[5] == Approx(1.0 - 11.0 / 32).margin(1e-6));
    CHECK(h[6] == Approx(11.0 / 32).margin(1e-6));
  }
  SECTION("cyan (hue 180 deg = level 128) is entirely in bin 4") {
    const auto h = patch(0, 255, 255);
    CHECK(h[4] == Approx(1.0));
  }
}

TEST_CASE("GIVEN a hue on the border between two bins WHEN histogrammed THEN it splits evenly") {
  // R=255, G=96, B=0: hue = 60 * 96/255 = 22.6 deg = level 16, halfway between bins 0 and 1.
  const auto h = patch(255, 96, 0);
  CHECK(h[0] == Approx(0.5).margin(1e-6));
  CHECK(h[1] == Approx(0.5).margin(1e-6));
}

TEST_CASE("GIVEN a red just below 360 degrees WHEN histogrammed THEN it wraps into bin 0") {
  // R=255, G=0, B=20: hue 355.3 deg = level 253, 3 levels before the red centre.
  const auto h = patch(255, 0, 20);
  CHECK(h[0] == Approx(29.0 / 32).margin(1e-6));
  CHECK(h[7] == Approx(3.0 / 32).margin(1e-6));
  CHECK(h[0] + h[7] == Approx(1.0));
}

TEST_CASE("GIVEN achromatic pixels WHEN histogrammed THEN they go to the grey bins") {
  CHECK(patch(255, 255, 255)[kWhite] == Approx(1.0));
  CHECK(patch(0, 0, 0)[kBlack] == Approx(1.0));
  const auto medium = patch(128, 128, 128);
  CHECK(medium[kMedium] == Approx(1.0 - 1.0 / 127.5).margin(1e-6));
  // Lightness 256/510 = 0.502 lies just above the medium centre: the remainder goes to light grey.
  CHECK(medium[kLight] == Approx(1.0 / 127.5).margin(1e-6));
  CHECK(medium[kDark] == 0.f);
}

TEST_CASE("GIVEN low-chroma colours WHEN histogrammed THEN chroma <= 12.5 % counts as grey") {
  // max - min = 31 <= 0.125 * 255: grey. 32: colour.
  const auto greyish = patch(160, 129, 129);
  float hue_mass = 0;
  for (int b = 0; b < kHueBins; ++b) hue_mass += greyish[b];
  CHECK(hue_mass == 0.f);
  const auto coloured = patch(161, 129, 129);
  CHECK(coloured[0] == Approx(1.0));
  // Lightness (160 + 129) / 510 = 0.567: between medium (0.5) and light (0.75), nearer medium.
  CHECK(greyish[kMedium] > greyish[kLight]);
  CHECK(greyish[kMedium] + greyish[kLight] == Approx(1.0));
}

TEST_CASE("GIVEN random images WHEN histogrammed over any column range THEN the bins sum to 1") {
  std::mt19937 rng(7);
  cv::Mat image(48, 64, CV_8UC3);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(256));
  HclHistogram histogram;
  for (int begin = 0; begin < 60; begin += 7) {
    const auto h = histogram.compute(image, begin, begin + 4);
    CHECK(sum(h) == Approx(1.0).margin(1e-5));
    for (float v : h) CHECK(v >= 0.f);
  }
  // An empty range has no pixels: all zero, no division by zero.
  CHECK(sum(histogram.compute(image, 10, 10)) == 0.f);
}

TEST_CASE("GIVEN the apexes are dropped WHEN black and white pixels are histogrammed THEN they do not count") {
  HclHistogramConfig config;
  config.min_lightness = 0.05;
  config.max_lightness = 0.95;
  cv::Mat image(10, 10, CV_8UC3, cv::Scalar(255, 255, 255));
  image(cv::Rect(0, 0, 5, 10)).setTo(cv::Scalar(0, 0, 255));  // half red
  const auto h = HclHistogram(config).compute(image, 0, 10);
  CHECK(h[0] == Approx(1.0));
  CHECK(h[kWhite] == 0.f);
}

TEST_CASE("GIVEN hue levels WHEN computed for primaries THEN they sit on the 256-level circle") {
  CHECK(HclHistogram::hueLevel(255, 0, 0) == 0.0);
  CHECK(HclHistogram::hueLevel(0, 255, 0) == 85.0);
  CHECK(HclHistogram::hueLevel(0, 0, 255) == 171.0);
}

TEST_CASE(
    "GIVEN a grey image WHEN histogrammed from its grey pixels THEN the bins equal those of its BGR copy") {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> level(0, 255);
  cv::Mat grey(37, 53, CV_8UC1), bgr;
  for (int y = 0; y < grey.rows; ++y)
    for (int x = 0; x < grey.cols; ++x) grey.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(level(rng));
  cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
  HclHistogramConfig apexes_dropped;
  apexes_dropped.min_lightness = 0.1;
  apexes_dropped.max_lightness = 0.8;
  for (const HclHistogramConfig& config : {HclHistogramConfig{}, apexes_dropped}) {
    const HclHistogram histogram(config);
    for (auto [begin, end] :
         {std::pair{0, 53}, std::pair{5, 6}, std::pair{10, 40}, std::pair{-3, 99}, std::pair{20, 20}}) {
      INFO("columns " << begin << " .. " << end << ", lightness from " << config.min_lightness);
      CHECK(histogram.computeGrey(grey, begin, end) == histogram.compute(bgr, begin, end));  // exactly
    }
  }
  CHECK_THROWS_WITH(HclHistogram().computeGrey(bgr, 0, 1), Catch::Contains("8-bit grey"));
}
