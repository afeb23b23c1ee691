// Tests of floor plans: YAML parsing and its error messages, the built-in worlds, the decoration.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "toposlam/sim/floor_plan.hpp"
#include "toposlam/sim/simulator.hpp"

using namespace toposlam::sim;

namespace {

/// A fresh folder of its own under the system temp dir (mkdtemp: parallel test runs never share it),
/// removed with everything in it when the test ends.
struct UniqueTempFolder {
  std::filesystem::path path;
  UniqueTempFolder() {
    std::string pattern = (std::filesystem::temp_directory_path() / "toposlam-floor-plan-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed for " + pattern);
    path = pattern;
  }
  ~UniqueTempFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  UniqueTempFolder(const UniqueTempFolder&) = delete;
  UniqueTempFolder& operator=(const UniqueTempFolder&) = delete;
};

const char* const kTwoRooms = R"(
name: flat
rooms:
  - name: left
    rect: [0, 0, 4, 3]
    wall: [200, 100, 50]
    posters: 2
  - name: right
    polygon: [[4, 0], [8, 0], [8, 3], [4, 3]]
    floor_pattern: tiles
doors:
  - {at: [4, 1.5], width: 1.0}
loop:
  - [2, 1.5]
  - {at: [6, 1.5], pause: 1.0}
  - [6, 2.2]
)";

std::string errorOf(const std::string& yaml) {
  try {
    parseFloorPlan(yaml, "test.yaml");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("GIVEN a YAML floor plan WHEN it is parsed THEN rooms, doors and the loop are as written", "[sim]") {
  World world = parseFloorPlan(kTwoRooms, "test.yaml");
  REQUIRE(world.rooms.size() == 2);
  CHECK(world.name == "flat");
  CHECK(world.rooms[0].wall_bgr == cv::Vec3b(50, 100, 200));  // YAML is RGB, stored BGR
  CHECK(world.rooms[1].floor_pattern == FloorPattern::Tiles);
  REQUIRE(world.doors.size() == 1);
  CHECK(world.doors[0].room_a + world.doors[0].room_b == 1);
  REQUIRE(world.loop.size() == 3);
  CHECK(world.loop[1].pause_s == 1.0);
  CHECK(world.roomContaining({1, 1}) == 0);
  CHECK(world.roomContaining({7, 1}) == 1);
  CHECK(world.placeLabel({4.1, 1.5}) == -1);  // in the doorway
  CHECK(world.placeLabel({4.5, 1.5}) == 1);

  // It renders through the same path as the built-in worlds, from a file.
  const UniqueTempFolder folder;
  const auto path = folder.path / "flat.yaml";
  std::ofstream(path) << kTwoRooms;
  SimConfig config;
  config.world = path.string();
  config.fps = 2;
  config.camera.width = 96;
  config.camera.height = 72;
  const Simulator simulator(config);
  CHECK(simulator.frameCount() > 5);
  CHECK(simulator.render(0).image.size() == cv::Size(96, 72));
}

TEST_CASE("GIVEN malformed floor plans WHEN parsed THEN the message names the offending key", "[sim]") {
  CHECK_THAT(errorOf("rooms: []"), Catch::Contains("rooms"));
  CHECK_THAT(errorOf("rooms:\n  - rect: [0, 0, 4]\n"), Catch::Contains("rooms[0].rect"));
  CHECK_THAT(errorOf("rooms:\n  - rect: [0, 0, 4, 3]\n    wall: [300, 0, 0]\n"), Catch::Contains("rooms[0].wall"));
  CHECK_THAT(errorOf("rooms:\n  - rect: [0, 0, 4, 3]\n    floor_pattern: marble\n"), Catch::Contains("carpet"));
  CHECK_THAT(errorOf("rooms:\n  - rect: [0, 0, 4, 3]\ndoors:\n  - {at: [9, 9]}\n"), Catch::Contains("doors[0].at"));
  CHECK_THAT(errorOf("rooms:\n  - rect: [0, 0, 4, 3]\nloop: [[1, 1], [9, 9]]\n"), Catch::Contains("loop[1]"));
  CHECK_THAT(errorOf("rooms: [ {rect: [0, 0"), Catch::Contains("test.yaml"));
  CHECK_THAT(errorOf("rooms:\n  - rect: [0, 0, 4, 3]\n    decoration_seed: -3\n"),
             Catch::Contains("rooms[0].decoration_seed: expected a whole number >= 0"));
  CHECK_THAT(errorOf("rooms:\n  - rect: [0, 0, 4, 3]\n    decoration_seed: many\n"),
             Catch::Contains("rooms[0].decoration_seed"));
  CHECK_THROWS_WITH(loadFloorPlanFile("/nonexistent/plan.yaml"), Catch::Contains("/nonexistent/plan.yaml"));
}

TEST_CASE("GIVEN the built-in worlds WHEN decorated THEN every room is furnished and nothing blocks the loop", "[sim]") {
  for (const std::string& name : builtinWorldNames()) {
    World world = loadWorld(name);
    CHECK(world.validate().empty());
    decorate(world, 1);
    for (const Room& room : world.rooms) {
      int decor = 0, furniture = 0;
      int signs = 0;
      for (const WallDecor& item : world.decor) {
        if (item.room != room.id) continue;
        (item.kind == DecorKind::Sign ? signs : decor) += 1;
      }
      CHECK(signs >= 5);  // small notices along every room's walls (about one per 1.5 m where free)
      for (const Furniture& item : world.furniture) furniture += item.room == room.id ? 1 : 0;
      INFO(name << " room " << room.name);
      CHECK(decor == room.posters + room.boards);
      CHECK(furniture == room.shelves + room.desks);
    }
    // The same seed decorates identically; another seed differently.
    World again = loadWorld(name);
    decorate(again, 1);
    REQUIRE(again.decor.size() == world.decor.size());
    CHECK(again.decor[0].u0 == world.decor[0].u0);
    World other = loadWorld(name);
    decorate(other, 2);
    CHECK(other.decor[0].u0 != world.decor[0].u0);
  }
}

TEST_CASE("GIVEN two rooms with one shape and one decoration seed WHEN decorated THEN they look alike whatever the world seed",
          "[sim]") {
  // tests/data/worlds/twins.yaml: "office A" (room 1) and "office A twin" (room 3) 12 m apart.
  const std::string path = TOPOSLAM_SAMPLES_DIR "/../worlds/twins.yaml";
  for (const std::uint64_t seed : {1u, 2u}) {
    World world = loadFloorPlanFile(path);
    REQUIRE(world.validate().empty());
    REQUIRE(world.rooms.size() == 5u);
    REQUIRE(world.rooms[1].decoration_seed == world.rooms[3].decoration_seed);
    decorate(world, seed);
    const auto decor_of = [&](int room) {
      std::vector<WallDecor> items;
      for (const WallDecor& d : world.decor)
        if (d.room == room) items.push_back(d);
      return items;
    };
    const std::vector<WallDecor> a = decor_of(1), twin = decor_of(3);
    REQUIRE(a.size() == twin.size());
    REQUIRE(a.size() >= 3u);  // 2 posters, 1 board, and signs
    for (std::size_t i = 0; i < a.size(); ++i) {
      CHECK(a[i].edge == twin[i].edge);
      CHECK(a[i].kind == twin[i].kind);
      CHECK(a[i].u0 == twin[i].u0);
      CHECK(a[i].v1 == twin[i].v1);
      CHECK(a[i].texture_seed == twin[i].texture_seed);
    }
    std::vector<Furniture> fa, ftwin;
    for (const Furniture& f : world.furniture) {
      if (f.room == 1) fa.push_back(f);
      if (f.room == 3) ftwin.push_back(f);
    }
    REQUIRE(fa.size() == ftwin.size());
    REQUIRE(fa.size() == 3u);  // 2 shelves, 1 desk
    for (std::size_t i = 0; i < fa.size(); ++i) {
      CHECK(std::abs(ftwin[i].centre.x - fa[i].centre.x - 12.0) < 1e-9);  // the twin is 12 m east
      CHECK(ftwin[i].centre.y == fa[i].centre.y);
      CHECK(ftwin[i].texture_seed == fa[i].texture_seed);
    }
  }
  // A room without its own seed still follows the world's.
  World one = loadFloorPlanFile(path), two = loadFloorPlanFile(path);
  decorate(one, 1);
  decorate(two, 2);
  const auto first_of = [](const World& w, int room) {
    for (const WallDecor& d : w.decor)
      if (d.room == room) return d.u0;
    return -1.0;
  };
  CHECK(first_of(one, 2) != first_of(two, 2));
  CHECK(first_of(one, 1) == first_of(two, 1));
}
