// End to end offline: simulator -> VPACK -> FiedlerSegmenter -> TopologyParticleFilter through the
// OfflineRunner that `toposlam map` uses, scored with src/eval's topology measures. The two-traversal
// office route must give the right topology: no node spans two rooms, no wrong loop closure, and the
// second traversal lands on the first traversal's nodes.
#include <catch2/catch.hpp>

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <set>

#include "mapping_fixture.hpp"

using namespace toposlam;
using toposlam::testing::MappingScore;

namespace {

/// Second-traversal places whose room was seen in the first traversal, and how many of them were put
/// on a node that holds a first-traversal place of the same room (the loop closed on the right node).
struct SecondTraversal {
  int places_in_known_rooms = 0;
  int on_first_traversal_node = 0;
};

SecondTraversal secondTraversal(const MappingScore& s) {
  std::map<int, std::set<int>> first_rooms_of_node;
  std::set<int> first_rooms;
  for (std::size_t k = 0; k < s.place_traversal.size(); ++k) {
    if (s.place_traversal[k] != 0 || s.place_room[k] < 0) continue;
    first_rooms_of_node[s.place_node[k]].insert(s.place_room[k]);
    first_rooms.insert(s.place_room[k]);
  }
  SecondTraversal r;
  for (std::size_t k = 0; k < s.place_traversal.size(); ++k) {
    if (s.place_traversal[k] != 1 || first_rooms.count(s.place_room[k]) == 0) continue;
    ++r.places_in_known_rooms;
    const auto it = first_rooms_of_node.find(s.place_node[k]);
    if (it != first_rooms_of_node.end() && it->second.count(s.place_room[k]) > 0) ++r.on_first_traversal_node;
  }
  return r;
}

void printScore(const char* route, const FiedlerSegmenterConfig& c, const MappingScore& s) {
  const SecondTraversal second = secondTraversal(s);
  std::printf(
      "%-12s w %2d floor %.2f g %.2f d %.2f | kept %2d drop %2d cuts %2zu F1@5 %.2f F1@15 %.2f | nodes %2d rooms %d "
      "1:1 %d merged %d split %d closures %2d wrong %d missed %d | 2nd %2d/%2d | pairs P %.3f R %.3f | p %.2f\n",
      route, c.window, c.similarity_floor, c.valley.gamma, c.valley.delta, s.kept, s.dropped, s.cuts.size(),
      s.boundaries_5.f1, s.boundaries_15.f1, s.topology.nodes, s.topology.rooms, s.topology.one_to_one,
      s.topology.merged_nodes, s.topology.split_rooms, s.topology.loop_closures, s.topology.wrong_loop_closures,
      s.topology.missed_loop_closures, second.on_first_traversal_node, second.places_in_known_rooms,
      s.closure_precision, s.closure_recall, s.best_probability);
}

}  // namespace

SCENARIO("The two-traversal simulated office gives the right topology", "[segmentation][topology][e2e]") {
  GIVEN("sim:office?route=loop2 (1618 frames, 320x240, 5 fps, seed 1) mapped with the default settings") {
    // Mapped once; Catch re-enters the scenario for every THEN.
    static const MappingScore s = [] {
      const testing::MappingRoute route = testing::simulatedRoute("office", "loop2");
      REQUIRE(route.fingerprints.size() == 1618);
      REQUIRE(route.traversal_starts.size() == 2);
      const NgramSimilarity similarity;
      FiedlerSegmenterConfig config;
      config.window = 30;  // 30 frames, 6 s at 5 fps
      MappingScore score = testing::mapRoute(route, config, similarity);
      printScore("office-loop2", config, score);
      return score;
    }();
    const SecondTraversal second = secondTraversal(s);
    INFO("places " << s.kept << " (+" << s.dropped << " dropped), nodes " << s.topology.nodes << ", one-to-one "
                   << s.topology.one_to_one << ", merged " << s.topology.merged_nodes << ", loop closures "
                   << s.topology.loop_closures << " (" << s.topology.wrong_loop_closures << " wrong, "
                   << s.topology.missed_loop_closures << " missed), second traversal " << second.on_first_traversal_node
                   << " of " << second.places_in_known_rooms << " on a first-traversal node of their room");
    THEN("every room yields a place and no place is dropped") {
      CHECK(s.topology.rooms == 6);
      CHECK(s.dropped == 0);
      CHECK(s.kept >= 16);  // 10 room visits per traversal; large rooms may give two places
      CHECK(s.kept <= 30);
    }
    THEN("no node stands for two rooms and no loop closure is wrong") {
      CHECK(s.topology.merged_nodes == 0);
      CHECK(s.topology.wrong_loop_closures == 0);
    }
    THEN("the loop is closed on the second traversal: its places land on the first traversal's nodes") {
      REQUIRE(second.places_in_known_rooms >= 8);
      CHECK(second.on_first_traversal_node >= second.places_in_known_rooms - 1);
      CHECK(s.topology.loop_closures >= 8);
      CHECK(s.topology.missed_loop_closures <= 5);
      CHECK(s.topology.nodes <= 15);
    }
  }
}

TEST_CASE("DETAIL of one configuration (TUNE_ROUTE=world, TUNE_CONFIG='window floor gamma delta')", "[.detail]") {
  const char* world = std::getenv("TUNE_ROUTE");
  const char* text = std::getenv("TUNE_CONFIG");
  FiedlerSegmenterConfig config;
  config.window = 30;  // a window of 30 frames (window_s 0), unless the text says otherwise
  if (text != nullptr) {
    std::istringstream in(text);
    in >> config.window >> config.similarity_floor >> config.valley.gamma >> config.valley.delta;
  }
  const testing::CachedSimilarity similarity;
  const std::string name = world ? world : "office";
  const testing::MappingRoute route = name == "samples" ? testing::sampleRoute() : testing::simulatedRoute(name, "loop2");
  const MappingScore s = testing::mapRoute(route, config, similarity);
  printScore(route.name.c_str(), config, s);
  for (std::size_t k = 0; k < s.places.size(); ++k) {
    const SegmentedPlace& p = s.places[k];
    std::string rooms;
    if (!route.rooms.empty()) {
      std::map<int, int> count;
      for (std::int64_t f = p.first_frame; f <= p.last_frame; ++f) ++count[route.rooms[static_cast<std::size_t>(f)]];
      for (const auto& [room, n] : count) rooms += " r" + std::to_string(room) + ":" + std::to_string(n);
    }
    std::printf("place %2zu frames %4lld-%4lld rep %4lld kp %3d room %2d node %2d |%s\n", k,
                static_cast<long long>(p.first_frame), static_cast<long long>(p.last_frame),
                static_cast<long long>(p.representative_frame), p.representative_keypoints,
                s.place_room.empty() ? -9 : s.place_room[k], s.place_node.empty() ? -9 : s.place_node[k], rooms.c_str());
  }
}

TEST_CASE("TUNE segmentation defaults on the simulated worlds and the samples", "[.tune]") {
  const testing::CachedSimilarity similarity;
  std::vector<testing::MappingRoute> routes;
  routes.push_back(testing::simulatedRoute("office", "loop2"));
  routes.push_back(testing::simulatedRoute("home", "loop2"));
  routes.push_back(testing::sampleRoute());
  // The grid behind docs/segmentation.md's table ("How the defaults were chosen"); a few minutes.
  for (int window : {25, 28, 30, 32, 35}) {
    for (double delta : {0.25, 0.3, 0.35}) {
      for (double floor : {0.0, 0.05, 0.08, 0.1}) {
        FiedlerSegmenterConfig config;
        config.window = window;
        config.valley.delta = delta;
        config.similarity_floor = floor;
        for (const auto& route : routes) {
          for (std::uint64_t seed : {1, 2, 3, 4}) {
            if (route.name == "samples" && seed > 1) break;  // no labels; loop closures only
            std::printf("seed %llu ", static_cast<unsigned long long>(seed));
            printScore(route.name.c_str(), config, testing::mapRoute(route, config, similarity, seed));
          }
        }
      }
    }
  }
}
