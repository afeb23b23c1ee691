// The simulated world as VPACK sees it (uses toposlam_fingerprint): the door frame is a detected
// vertical edge at its projected column; different rooms differ in their HCL histograms more than two
// frames of the same room do, in the office (look-alike white and grey rooms) and in the home (colourful,
// varied rooms that on average differ more, and carry more chromatic mass, than the offices).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string>

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

/// Whole-frame HCL histograms of every other frame of one loop, by room (doorway frames left out), their
/// per-room means, and the mean L1 distance between consecutive sampled frames of one room.
struct RoomHistograms {
  std::map<int, HclHistogramBins> mean;
  double within = 0;
  double between(int a, int b) const { return l1(mean.at(a), mean.at(b)); }
  /// Share of the histogram in the 8 hue bins (the rest is grey): how colourful a room is, 0..1.
  double chromatic(int room) const {
    double sum = 0;
    for (int i = 0; i < kHueBins; ++i) sum += mean.at(room)[static_cast<std::size_t>(i)];
    return sum;
  }
};

RoomHistograms roomHistograms(const std::string& world) {
  SimConfig config;
  config.world = world;
  config.route = "loop";
  config.fps = 5;
  const Simulator simulator(config);
  const HclHistogram histogram;
  std::map<int, std::vector<HclHistogramBins>> per_room;
  for (std::int64_t frame = 0; frame < simulator.frameCount(); frame += 2) {
    const SimFrame rendered = simulator.render(frame);
    if (rendered.truth.room < 0) continue;
    per_room[rendered.truth.room].push_back(histogram.compute(rendered.image, 0, rendered.image.cols));
  }
  RoomHistograms out;
  int within_count = 0;
  for (const auto& [room, histograms] : per_room) {
    HclHistogramBins mean{};
    for (const auto& h : histograms) {
      for (std::size_t i = 0; i < mean.size(); ++i) mean[i] += h[i] / static_cast<float>(histograms.size());
    }
    out.mean[room] = mean;
    for (std::size_t i = 1; i < histograms.size(); ++i) {
      out.within += l1(histograms[i - 1], histograms[i]);
      ++within_count;
    }
  }
  out.within /= std::max(1, within_count);
  return out;
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
  const RoomHistograms office = roomHistograms("office");
  REQUIRE(office.mean.size() == 6);
  // Offices 1..4 look alike (white and grey), yet every pair differs more than neighbouring frames do.
  for (int a = 1; a <= 4; ++a) {
    for (int b = a + 1; b <= 4; ++b) {
      INFO("offices " << a << " and " << b << ": between " << office.between(a, b) << ", within "
                      << office.within);
      CHECK(office.between(a, b) > office.within);
    }
  }
}

TEST_CASE(
    "GIVEN the home world WHEN its rooms' HCL histograms are compared THEN every pair of rooms differs more "
    "than frames of one room, and the rooms differ more and are more colourful than the offices",
    "[sim][vpack]") {
  const RoomHistograms home = roomHistograms("home");
  const RoomHistograms office = roomHistograms("office");
  REQUIRE(home.mean.size() == 5);  // hall, living room, kitchen, bedroom, bathroom
  double office_between = 0;
  int office_pairs = 0;
  for (int a = 1; a <= 4; ++a) {
    for (int b = a + 1; b <= 4; ++b) {
      office_between += office.between(a, b);
      ++office_pairs;
    }
  }
  office_between /= office_pairs;
  double home_between = 0;
  int home_pairs = 0;
  for (int a = 0; a < 5; ++a) {
    for (int b = a + 1; b < 5; ++b) {
      INFO("home rooms " << a << " and " << b << ": between " << home.between(a, b) << ", within "
                         << home.within);
      CHECK(home.between(a, b) > home.within);
      home_between += home.between(a, b);
      ++home_pairs;
    }
  }
  home_between /= home_pairs;
  // Varied: on average two home rooms differ clearly more than two offices (hall and living room, both warm
  // walls on wood, are the closest pair at ~0.42 against ~0.55 for the mean office pair).
  INFO("mean home pair " << home_between << ", mean office pair " << office_between);
  CHECK(home_between > 1.4 * office_between);
  // Colourful: every home room has more of its histogram in the hue bins (measured >= 0.51) than the most
  // colourful office (measured ~0.20).
  double office_max_chromatic = 0;
  for (int room = 1; room <= 4; ++room)
    office_max_chromatic = std::max(office_max_chromatic, office.chromatic(room));
  for (int room = 0; room < 5; ++room) {
    INFO("home room " << room << " chromatic share " << home.chromatic(room) << ", offices at most "
                      << office_max_chromatic);
    CHECK(home.chromatic(room) > office_max_chromatic);
  }
}
