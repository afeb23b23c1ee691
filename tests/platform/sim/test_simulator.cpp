// Tests of the simulated world: determinism, ground truth that agrees with the pose, routes, variation
// switches and the loop-closure matrix.
#include <catch2/catch.hpp>

#include <cmath>
#include <set>

#include <opencv2/core.hpp>

#include "toposlam/sim/floor_plan.hpp"
#include "toposlam/sim/simulator.hpp"

using namespace toposlam::sim;

namespace {

SimConfig smallConfig(const std::string& world = "office", const std::string& route = "loop") {
  SimConfig config;
  config.world = world;
  config.route = route;
  config.fps = 2;
  config.camera.width = 160;
  config.camera.height = 120;
  return config;
}

double differingPixels(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat difference;
  cv::absdiff(a, b, difference);
  return cv::countNonZero(difference.reshape(1));
}

}  // namespace

TEST_CASE("GIVEN one seed WHEN two simulators render the same frames THEN the pixels are identical", "[sim]") {
  SimConfig config = smallConfig();
  config.people = 3;
  config.noise_sigma = 3;
  config.pitch_deg = 2;
  const Simulator first(config);
  const Simulator second(config);
  REQUIRE(first.frameCount() == second.frameCount());
  for (const std::int64_t frame : {std::int64_t{0}, std::int64_t{37}, first.frameCount() - 1}) {
    const SimFrame a = first.render(frame);
    const SimFrame b = second.render(frame);
    REQUIRE(a.image.type() == CV_8UC3);
    REQUIRE(a.image.size() == cv::Size(160, 120));
    CHECK(differingPixels(a.image, b.image) == 0);
    CHECK(a.truth.pose.x == b.truth.pose.x);
  }
  // Random access and sequential access agree.
  Simulator sequential(config);
  const auto first_frame = sequential.next();
  REQUIRE(first_frame.has_value());
  CHECK(differingPixels(first_frame->image, first.render(0).image) == 0);
}

TEST_CASE("GIVEN two seeds WHEN the same frame is rendered THEN the pictures differ", "[sim]") {
  SimConfig config = smallConfig();
  const Simulator one(config);
  config.seed = 2;
  const Simulator two(config);
  // Same route, so same poses; the decoration (posters, furniture) differs somewhere along it.
  double total_difference = 0;
  for (std::int64_t frame = 0; frame < one.frameCount(); frame += 10) {
    CHECK(one.truthOf(frame).pose.x == two.truthOf(frame).pose.x);
    total_difference += differingPixels(one.render(frame).image, two.render(frame).image);
  }
  CHECK(total_difference > 1000);
}

TEST_CASE("GIVEN the office loop WHEN every frame's label is checked THEN it agrees with the pose", "[sim]") {
  const Simulator simulator(smallConfig("office", "loop2"));
  const World& world = simulator.world();
  std::set<int> rooms_seen;
  int doorway_frames = 0;
  for (std::int64_t frame = 0; frame < simulator.frameCount(); ++frame) {
    const GroundTruth truth = simulator.truthOf(frame);
    const Point position(truth.pose.x, truth.pose.y);
    // Independent lookup: which room polygon contains the camera.
    int polygon_room = -1;
    for (const Room& room : world.rooms) {
      if (polygonContains(room.polygon, position)) {
        polygon_room = room.id;
        break;
      }
    }
    REQUIRE(polygon_room >= 0);  // the camera never leaves the building
    if (truth.room >= 0) {
      CHECK(truth.room == polygon_room);
      rooms_seen.insert(truth.room);
    } else {
      ++doorway_frames;
      CHECK(world.placeLabel(position, 0.25) == -1);
    }
    CHECK(std::abs(truth.time_s - frame / 2.0) < 1e-9);
  }
  CHECK(rooms_seen.size() == 6);  // corridor, four offices, printer room
  CHECK(doorway_frames > 0);
  CHECK(doorway_frames < simulator.frameCount() / 10);
  // Second traversal: traversal index 1 on the last frame, the same rooms in the same order.
  CHECK(simulator.truthOf(simulator.frameCount() - 1).traversal == 1);
}

TEST_CASE("GIVEN labels WHEN the loop-closure matrix is built THEN earlier frames of the same room are marked", "[sim]") {
  const std::vector<int> labels = {0, 0, 1, -1, 0, 1};
  const cv::Mat matrix = loopClosureMatrix(labels);
  REQUIRE(matrix.size() == cv::Size(6, 6));
  REQUIRE(matrix.type() == CV_8UC1);
  CHECK(matrix.at<unsigned char>(1, 0) == 255);
  CHECK(matrix.at<unsigned char>(0, 1) == 0);    // only earlier frames (lower triangle, like samples_GT.bmp)
  CHECK(matrix.at<unsigned char>(4, 0) == 255);
  CHECK(matrix.at<unsigned char>(4, 1) == 255);
  CHECK(matrix.at<unsigned char>(4, 2) == 0);
  CHECK(matrix.at<unsigned char>(5, 2) == 255);
  CHECK(cv::countNonZero(matrix.row(3)) == 0);   // doorway frames match nothing
  CHECK(cv::countNonZero(matrix.col(3)) == 0);
  CHECK(cv::countNonZero(matrix) == 4);  // (1,0) (4,0) (4,1) (5,2)
  const cv::Mat gapped = loopClosureMatrix(labels, 2);  // ignore the 2 previous frames
  CHECK(gapped.at<unsigned char>(1, 0) == 0);
  CHECK(gapped.at<unsigned char>(4, 0) == 255);
  CHECK(gapped.at<unsigned char>(4, 1) == 255);
  CHECK(gapped.at<unsigned char>(5, 2) == 255);
}

TEST_CASE("GIVEN the route names WHEN trajectories are built THEN traversals, directions and pauses are as named", "[sim]") {
  World world = loadWorld("office");
  RouteConfig motion;
  const Trajectory loop = buildTrajectory(world, "loop", motion, 1);
  const Trajectory loop2 = buildTrajectory(world, "loop2", motion, 1);
  const Trajectory both = buildTrajectory(world, "both", motion, 1);
  const Trajectory stopgo = buildTrajectory(world, "stopgo", motion, 1);
  // The loop is closed: it ends where it starts; two traversals take twice as long (plus one turn).
  const Pose start = loop.poseAt(0), end = loop.poseAt(loop.duration());
  CHECK(std::hypot(start.x - end.x, start.y - end.y) < 1e-9);
  CHECK(loop2.duration() >= 2 * loop.duration());
  CHECK(loop2.duration() < 2 * loop.duration() + 4.0);
  CHECK(loop2.traversalAt(loop.duration() / 2) == 0);
  CHECK(loop2.traversalAt(loop2.duration() - 1) == 1);
  // Both directions: the second traversal visits the rooms in the reverse order of the first.
  std::vector<int> forward_rooms, backward_rooms;
  for (double t = 0; t <= both.duration(); t += 0.2) {
    const Pose pose = both.poseAt(t);
    const int room = world.placeLabel({pose.x, pose.y});
    std::vector<int>& rooms = both.traversalAt(t) == 0 ? forward_rooms : backward_rooms;
    if (room >= 0 && (rooms.empty() || rooms.back() != room)) rooms.push_back(room);
  }
  CHECK(forward_rooms == std::vector<int>{0, 2, 3, 0, 4, 0, 5, 0, 1, 0});
  CHECK(backward_rooms == std::vector<int>(forward_rooms.rbegin(), forward_rooms.rend()));
  CHECK(std::abs(both.poseAt(5.0).heading) < 1e-6);  // driving east along the corridor first
  // Stop and go: pauses (the pose stays put for over a second somewhere) and a different duration.
  bool paused = false;
  for (double t = 0; t + 1.2 < stopgo.duration(); t += 0.1) {
    const Pose a = stopgo.poseAt(t), b = stopgo.poseAt(t + 1.2);
    if (a.x == b.x && a.y == b.y && a.heading == b.heading) paused = true;
  }
  CHECK(paused);
  CHECK(std::abs(stopgo.duration() - loop2.duration()) > 1.0);
  // Unknown route: the message names the allowed ones.
  try {
    buildTrajectory(world, "figure8", motion, 1);
    FAIL("expected an exception");
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    CHECK(message.find("figure8") != std::string::npos);
    CHECK(message.find("loop2") != std::string::npos);
    CHECK(message.find("corridor") != std::string::npos);
  }
}

TEST_CASE("GIVEN variation switches WHEN frames are rendered THEN each switch changes the picture as intended", "[sim]") {
  const SimConfig base = smallConfig("home", "loop");
  const Simulator plain(base);
  const std::int64_t frame = 12;
  const cv::Mat reference = plain.render(frame).image;

  SECTION("night is darker and warmer than day") {
    SimConfig config = base;
    config.lighting = LightingMode::Night;
    const cv::Scalar day = cv::mean(reference), night = cv::mean(Simulator(config).render(frame).image);
    CHECK(night[0] + night[1] + night[2] < 0.7 * (day[0] + day[1] + day[2]));
    CHECK(night[2] / night[0] > day[2] / day[0]);  // more red than blue, relative to day
  }
  SECTION("sensor noise keeps the mean and spreads the pixels") {
    SimConfig config = base;
    config.noise_sigma = 8;
    const cv::Mat noisy = Simulator(config).render(frame).image;
    cv::Mat difference;
    cv::subtract(noisy, reference, difference, cv::noArray(), CV_32F);
    cv::Scalar mean, stddev;
    cv::meanStdDev(difference.reshape(1), mean, stddev);
    CHECK(std::abs(mean[0]) < 1.0);
    CHECK(stddev[0] > 6.0);
    CHECK(stddev[0] < 9.0);
  }
  SECTION("pitch moves the horizon") {
    SimConfig config = base;
    config.pitch_deg = 5;
    CHECK(differingPixels(Simulator(config).render(frame).image, reference) > 1000);
  }
  SECTION("people appear in some frames") {
    SimConfig config = base;
    config.people = 6;
    const Simulator crowded(config);
    double difference = 0;
    for (std::int64_t f = 0; f < plain.frameCount(); f += 5) {
      difference += differingPixels(crowded.render(f).image, plain.render(f).image);
    }
    CHECK(difference > 500);
  }
  SECTION("moved furniture changes the second traversal only") {
    SimConfig config = smallConfig("office", "loop2");
    const Simulator still(config);
    config.moved_furniture = true;
    const Simulator moved(config);
    double first_difference = 0, second_difference = 0;
    for (std::int64_t f = 0; f < still.frameCount(); f += 3) {
      const double d = differingPixels(moved.render(f).image, still.render(f).image);
      (still.truthOf(f).traversal == 0 ? first_difference : second_difference) += d;
    }
    CHECK(first_difference == 0);
    CHECK(second_difference > 1000);
  }
}

TEST_CASE("GIVEN bad simulator settings WHEN a simulator is built THEN the message names the key", "[sim]") {
  auto message_of = [](const SimConfig& config) {
    try {
      Simulator simulator(config);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  SimConfig config = smallConfig();
  config.fps = 0;
  CHECK(message_of(config).find("fps") != std::string::npos);
  config = smallConfig();
  config.noise_sigma = 99;
  CHECK(message_of(config).find("noise") != std::string::npos);
  config = smallConfig();
  config.world = "castle";
  const std::string unknown_world = message_of(config);
  CHECK(unknown_world.find("castle") != std::string::npos);
  CHECK(unknown_world.find("office") != std::string::npos);
  config = smallConfig();
  config.world = "/nonexistent/plan.yaml";
  CHECK(message_of(config).find("/nonexistent/plan.yaml") != std::string::npos);
  CHECK_THROWS_WITH(parseLightingMode("dusk"), Catch::Contains("night"));
}
