// Tests of the ray caster's geometry: a door frame at a known world position projects to the expected
// image column and gives a strong vertical-edge response there (|Sobel x| column sums, computed here
// without the VPACK code).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include <opencv2/imgproc.hpp>

#include "toposlam/sim/floor_plan.hpp"
#include "toposlam/sim/renderer.hpp"

using namespace toposlam::sim;

namespace {

std::vector<double> sobelColumnResponse(const cv::Mat& bgr) {
  cv::Mat grey, sobel;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  cv::Sobel(grey, sobel, CV_32F, 1, 0);
  sobel = cv::abs(sobel);
  std::vector<double> response(static_cast<std::size_t>(bgr.cols));
  for (int x = 0; x < bgr.cols; ++x) response[static_cast<std::size_t>(x)] = cv::sum(sobel.col(x))[0];
  return response;
}

}  // namespace

TEST_CASE("GIVEN a door frame at a known position WHEN rendered THEN it projects to the expected column with a "
          "strong edge", "[sim]") {
  // Office, undecorated: the door of office 2 opens at x = 8 +- 0.45 in the wall y = 2.2; its frame strips
  // cover x in [7.45, 7.55] and [8.45, 8.55]. The camera stands in the corridor facing north.
  const World world = loadWorld("office");
  const Scene scene(world);
  CameraConfig camera;  // 320 x 240, 60 degrees
  const Renderer renderer(camera);
  const Pose pose{7.0, 0.3, std::numbers::pi / 2};
  cv::Mat image;
  renderer.render(scene, pose, 0.0, Lighting{}, {}, {}, image);
  REQUIRE(image.size() == cv::Size(320, 240));

  // Pinhole projection by hand: f = 160 / tan(30 deg) = 277.13 px; the frame's outer edge (x = 7.45) is
  // 0.45 m right of the camera at 1.9 m depth.
  const double focal = 160.0 / std::tan(std::numbers::pi / 6);
  const double expected_column = 160.0 + focal * 0.45 / 1.9;  // 225.6
  CHECK(renderer.projectColumn(pose, {7.45, 2.2}) == Approx(expected_column).margin(1e-9));
  CHECK(renderer.focalPixels() == Approx(focal));

  const std::vector<double> response = sobelColumnResponse(image);
  std::vector<double> sorted = response;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  const int column = static_cast<int>(std::lround(expected_column));
  const double near_frame = *std::max_element(response.begin() + column - 2, response.begin() + column + 3);
  CHECK(near_frame > 5 * median);
  // The strongest columns of the whole image are the four edges of the two frame strips.
  const auto strongest = std::max_element(response.begin(), response.end()) - response.begin();
  const std::vector<double> frame_columns = {renderer.projectColumn(pose, {7.45, 2.2}),
                                             renderer.projectColumn(pose, {7.55, 2.2}),
                                             renderer.projectColumn(pose, {8.45, 2.2}),
                                             renderer.projectColumn(pose, {8.55, 2.2})};
  const double closest = std::accumulate(frame_columns.begin(), frame_columns.end(), 1e9, [&](double best, double c) {
    return std::min(best, std::abs(c - static_cast<double>(strongest)));
  });
  CHECK(closest <= 2.0);
  // Through the opening we see into office 2: its walls, not the corridor's colour at eye level.
  const cv::Vec3b inside = image.at<cv::Vec3b>(120, static_cast<int>(renderer.projectColumn(pose, {8.0, 2.2})));
  const cv::Vec3b frame_pixel = image.at<cv::Vec3b>(120, static_cast<int>(std::lround(renderer.projectColumn(pose, {7.5, 2.2}))));
  CHECK(frame_pixel[0] < 80);  // dark door frame
  CHECK(inside[0] > frame_pixel[0] + 25);  // the lighter wall of the office behind the door
}

TEST_CASE("GIVEN a room corner WHEN rendered THEN the two walls differ in brightness (a vertical edge)", "[sim]") {
  const World world = loadWorld("office");
  const Scene scene(world);
  const Renderer renderer(CameraConfig{});
  // In office 1 (x 0..6, y 2.2..7.2) looking at its north-west corner (0, 7.2) from the room's middle.
  const Pose pose{3.0, 4.7, std::atan2(7.2 - 4.7, 0.0 - 3.0)};
  cv::Mat image;
  renderer.render(scene, pose, 0.0, Lighting{}, {}, {}, image);
  const int corner = static_cast<int>(std::lround(renderer.projectColumn(pose, {0.0, 7.2})));
  REQUIRE(corner > 10);
  REQUIRE(corner < 310);
  const cv::Vec3b left = image.at<cv::Vec3b>(100, corner - 6), right = image.at<cv::Vec3b>(100, corner + 6);
  CHECK(std::abs(static_cast<int>(left[1]) - static_cast<int>(right[1])) > 30);
}
