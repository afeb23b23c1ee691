// The simulated world as VPACK sees it (uses toposlam_fingerprint): the door frame is a detected
// vertical edge at its projected column, and different office rooms differ in their HCL histograms
// more than two frames of the same room do.
#include <catch2/catch.hpp>

#include <cmath>
#include <map>
#include <numbers>

#include "toposlam/fingerprint/hcl_histogram.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/sim/floor_plan.hpp"
#include "toposlam/sim/renderer.hpp"
#include "toposlam/sim/simulator.hpp"

using namespace toposlam;
using namespace toposlam::sim;

namespace {

double l1(const HclHistogramBins& a, const HclHistogramBins& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += std::abs(a[i] - b[i]);
  return sum;
}

}  // namespace

TEST_CASE("GIVEN a door frame in view WHEN VPACK extracts edges THEN one lies within 3 px of its projected column",
          "[sim][vpack]") {
  World world = loadWorld("office");
  decorate(world, 1);
  const Scene scene(world);
  const Renderer renderer(CameraConfig{});
  const Pose pose{7.0, 0.3, std::numbers::pi / 2};
  cv::Mat image;
  renderer.render(scene, pose, 0.0, Lighting{}, {}, {}, image);
  const Fingerprint fingerprint = VpackExtractor().extract(image);
  REQUIRE_FALSE(fingerprint.edge_columns.empty());
  // The left frame strip (x 7.45..7.55 m) is in view at columns ~226..240; its two sides are 15 px apart,
  // closer than the NMS separation (16 px), so VPACK keeps one of them.
  const double left_side = renderer.projectColumn(pose, {7.45, 2.2});
  const double right_side = renderer.projectColumn(pose, {7.55, 2.2});
  CHECK(left_side == Approx(225.6).margin(0.1));
  double closest = 1e9;
  for (const int column : fingerprint.edge_columns) {
    closest = std::min({closest, std::abs(column - left_side), std::abs(column - right_side)});
  }
  INFO("door frame sides project to columns " << left_side << " and " << right_side);
  CHECK(closest <= 3.0);
}

TEST_CASE("GIVEN two office rooms WHEN their frames' HCL histograms are compared THEN rooms differ more than frames "
          "of one room", "[sim][vpack]") {
  SimConfig config;
  config.world = "office";
  config.route = "loop";
  config.fps = 5;
  const Simulator simulator(config);
  const HclHistogram histogram;
  // Mean histogram of the frames in each room; and the spread between consecutive frames of one room.
  std::map<int, std::vector<HclHistogramBins>> per_room;
  for (std::int64_t frame = 0; frame < simulator.frameCount(); frame += 2) {
    const SimFrame rendered = simulator.render(frame);
    if (rendered.truth.room < 0) continue;
    per_room[rendered.truth.room].push_back(histogram.compute(rendered.image, 0, rendered.image.cols));
  }
  REQUIRE(per_room.size() == 6);
  auto mean_of = [](const std::vector<HclHistogramBins>& histograms) {
    HclHistogramBins mean{};
    for (const auto& h : histograms) {
      for (std::size_t i = 0; i < mean.size(); ++i) mean[i] += h[i] / static_cast<float>(histograms.size());
    }
    return mean;
  };
  double within = 0;
  int within_count = 0;
  for (const auto& [room, histograms] : per_room) {
    for (std::size_t i = 1; i < histograms.size(); ++i) {
      within += l1(histograms[i - 1], histograms[i]);
      ++within_count;
    }
  }
  within /= within_count;
  // Offices 1..4 look alike (white and grey), yet every pair differs more than neighbouring frames do.
  for (int a = 1; a <= 4; ++a) {
    for (int b = a + 1; b <= 4; ++b) {
      const double between = l1(mean_of(per_room[a]), mean_of(per_room[b]));
      INFO("offices " << a << " and " << b << ": between " << between << ", within " << within);
      CHECK(between > within);
    }
  }
}
