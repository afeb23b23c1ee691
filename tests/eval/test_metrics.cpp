// Evaluation measures on hand-made inputs whose answers are worked out by hand in the comments.
#include <catch2/catch.hpp>

#include <cmath>

#include "toposlam/eval/metrics.hpp"

using namespace toposlam::eval;

SCENARIO(
    "GIVEN six localisation predictions WHEN tabulated at the thesis thresholds THEN counts and precision "
    "match Table 3.1's definition") {
  // (predicted, truth, probability): correct at 0.95, 0.75, 0.55, 0.5; wrong at 0.85 and 0.45.
  const std::vector<LocalisationPrediction> predictions = {{"A", "A", 0.95}, {"A", "B", 0.85},
                                                           {"B", "B", 0.75}, {"B", "B", 0.55},
                                                           {"C", "A", 0.45}, {"A", "A", 0.5}};
  const auto rows = localisationTable(predictions, defaultThresholds());
  REQUIRE(rows.size() == 5);
  CHECK(rows[0].threshold == 0.5);
  CHECK(rows[0].images == 5);  // 0.5 itself counts (>=)
  CHECK(rows[0].correct == 4);
  CHECK(rows[0].precision == Approx(0.8));
  CHECK(rows[1].images == 3);
  CHECK(rows[1].precision == Approx(2.0 / 3.0));
  CHECK(rows[2].images == 3);
  CHECK(rows[3].images == 2);
  CHECK(rows[3].precision == Approx(0.5));
  CHECK(rows[4].images == 1);
  CHECK(rows[4].precision == Approx(1.0));
  WHEN("no prediction reaches a threshold") {
    const auto empty = localisationTable({{"A", "A", 0.3}}, {0.9});
    THEN("it has 0 images and an undefined precision") {
      CHECK(empty[0].images == 0);
      CHECK(std::isnan(empty[0].precision));
    }
  }
}

SCENARIO(
    "GIVEN rooms 0,1,0,1 (four visits) and nodes 0,1,0,0 WHEN the loop-closure curve is computed THEN recall "
    "at 100 % precision is 0.5") {
  // Positives: (2,0) and (3,1). Predicted pairs (node 0 in different visits: frame 0, then frames 2-3):
  // (2,0) score 0.9 TP, (3,0) score 0.4 FP; (3,2) is within one visit of node 0, no loop closure.
  const LoopClosureTruth truth = truthFromRooms({0, 1, 0, 1}, 0);
  CHECK(truth.positives() == 2);
  CHECK(truth.at(1, 0) == 0);
  CHECK(truth.at(0, 2) == 1);
  const auto pairs = pairsFromAssignments({0, 1, 0, 0}, {1.0, 1.0, 0.9, 0.4});
  CHECK(pairs.size() == 2);
  const PrCurve curve = precisionRecall(truth, pairs);
  REQUIRE(curve.points.size() == 2);
  CHECK(curve.points[0].threshold == Approx(0.9));
  CHECK(curve.points[0].true_positives == 1);
  CHECK(curve.points[0].false_positives == 0);
  CHECK(curve.points[0].precision == Approx(1.0));
  CHECK(curve.points[0].recall == Approx(0.5));
  CHECK(curve.points[1].false_positives == 1);
  CHECK(curve.points[1].precision == Approx(0.5));
  CHECK(curve.recall_at_full_precision == Approx(0.5));
  CHECK(curve.threshold_at_full_precision == Approx(0.9));
  CHECK(curve.average_precision == Approx(0.5));  // 0.5 x 1 + 0 x 1/2
}

SCENARIO(
    "GIVEN node and room labels with doorway frames WHEN visits are numbered THEN a visit is a run of one "
    "label and -1 frames neither end nor start one") {
  CHECK(visitIds({0, 0, -1, 0, 1, 1, -1, 0}) == std::vector<int>{0, 0, -1, 0, 1, 1, -1, 2});
  CHECK(visitIds({-1, 3, 3, 5, 3}) == std::vector<int>{-1, 0, 0, 1, 2});
  CHECK(visitIds({}).empty());
}

SCENARIO(
    "GIVEN a first place that straddles a room change WHEN loop closures are scored THEN pairs inside the "
    "place are no prediction and recall at 100 % precision is that of the real revisit") {
  // Places: P0 frames 0-3 (rooms 0,0,1,1) on node 0 at p = 1.0; P1 frames 4-5 (room 2) on node 1 at 0.95;
  // P2 frames 6-7 (room 0) on a new node 2 at 0.9 (a missed closure); P3 frames 8-9 (room 2) back on node 1
  // at 0.8 (a right closure).
  const std::vector<int> rooms = {0, 0, 1, 1, 2, 2, 0, 0, 2, 2};
  const std::vector<int> nodes = {0, 0, 0, 0, 1, 1, 2, 2, 1, 1};
  const std::vector<double> p = {1.0, 1.0, 1.0, 1.0, 0.95, 0.95, 0.9, 0.9, 0.8, 0.8};
  const LoopClosureTruth truth = truthFromRooms(rooms, 0);
  // Room 0: {0,1} x {6,7}; room 2: {4,5} x {8,9}; room 1 is visited once.
  CHECK(truth.positives() == 8);
  // Inside P0, (2,0) crosses the room change: a true negative of the truth (different rooms and visits).
  CHECK(truth.at(2, 0) == 0);
  const auto pairs = pairsFromAssignments(nodes, p);
  // Only the revisit of node 1 claims a loop closure: (8,4), (8,5), (9,4), (9,5). Counting the pairs inside
  // P0 as predictions (the old reading) would add (2,0), (2,1), (3,0), (3,1) as false positives at score 1.0
  // and pin recall at 100 % precision to 0.
  REQUIRE(pairs.size() == 4);
  for (const ScoredPair& pair : pairs) {
    CHECK(nodes[static_cast<std::size_t>(pair.i)] == 1);
    CHECK(pair.i >= 8);
    CHECK(pair.j <= 5);
    CHECK(pair.score == Approx(0.8));
  }
  const PrCurve curve = precisionRecall(truth, pairs);
  CHECK(curve.predicted == 4);
  REQUIRE(curve.points.size() == 1);
  CHECK(curve.points[0].true_positives == 4);
  CHECK(curve.points[0].false_positives == 0);
  CHECK(curve.recall_at_full_precision == Approx(0.5));
  CHECK(curve.threshold_at_full_precision == Approx(0.8));
  CHECK(curve.average_precision == Approx(0.5));
}

SCENARIO(
    "GIVEN one room visit split by a doorway WHEN loop-closure truth is built THEN pairs within a visit are "
    "not evaluated") {
  // rooms 0,0,1,1,0,0: visits {0,1}, {2,3}, {4,5}; positives (4,0),(4,1),(5,0),(5,1); (1,0),(3,2),(5,4)
  // ignored.
  const LoopClosureTruth truth = truthFromRooms({0, 0, 1, 1, 0, 0}, 0);
  CHECK(truth.positives() == 4);
  CHECK(truth.at(1, 0) == -1);
  CHECK(truth.at(5, 4) == -1);
  CHECK(truth.at(2, 0) == 0);
  // Frames 0,1,4 on node 0: (1,0) is ignored, (4,0) and (4,1) are true positives at score 0.8.
  const PrCurve curve =
      precisionRecall(truth, pairsFromAssignments({0, 0, 1, 1, 0, 2}, {1, 1, 0.9, 0.9, 0.8, 0.6}));
  REQUIRE(curve.points.size() == 1);
  CHECK(curve.predicted == 2);
  CHECK(curve.recall_at_full_precision == Approx(0.5));
  WHEN("a pair lies outside the truth") {
    THEN("it throws") { CHECK_THROWS_AS(precisionRecall(truth, {ScoredPair{9, 0, 1.0}}), std::out_of_range); }
  }
}

SCENARIO(
    "GIVEN a 4x4 loop-closure matrix WHEN neighbours within 1 frame are excluded THEN only far pairs are "
    "evaluated") {
  LoopClosureMatrix m;
  m.size = 4;
  m.same.assign(16, 0);
  m.same[3 * 4 + 0] = 1;  // frame 3 revisits frame 0 (lower triangle only, like samples_GT.bmp)
  m.same[0 * 4 + 3] = 1;
  const LoopClosureTruth truth = truthFromMatrix(m, 1);
  CHECK(truth.positives() == 1);
  CHECK(truth.at(1, 0) == -1);
  CHECK(truth.at(2, 0) == 0);
  CHECK(truth.at(3, 1) == 0);
  CHECK(truth.at(3, 2) == -1);
}

SCENARIO(
    "GIVEN rooms with a doorway and a direct change WHEN boundaries are derived THEN the doorway gives an "
    "interval") {
  const auto b = roomBoundaries({0, 0, -1, -1, 1, 1, 1, 0, 0}, {0});
  REQUIRE(b.size() == 2);
  CHECK(b[0].from == 2);
  CHECK(b[0].to == 4);
  CHECK(b[1].from == 7);
  CHECK(b[1].to == 7);
  CHECK(roomBoundaries({0, -1, 0}, {0}).empty());                 // stepped into a doorway and back
  CHECK(roomBoundaries({0, 0, 1, 1, 0, 0}, {0, 4}).size() == 1);  // no boundary at a traversal start

  WHEN("cuts 3, 9, 20 are scored with tolerance 2") {
    const BoundaryScore s = scoreBoundaries({3, 9, 20}, b, 2);
    THEN("two match: precision 2/3, recall 1, F1 0.8") {
      CHECK(s.matched == 2);
      CHECK(s.precision == Approx(2.0 / 3.0));
      CHECK(s.recall == Approx(1.0));
      CHECK(s.f1 == Approx(0.8));
      CHECK(s.mean_offset == Approx(1.0));  // 3 inside [2, 4]: 0; 9 after [7, 7]: +2
    }
  }
  WHEN("the tolerance is 1") {
    const BoundaryScore s = scoreBoundaries({3, 9, 20}, b, 1);
    THEN("only the cut inside the doorway matches: F1 0.4") {
      CHECK(s.matched == 1);
      CHECK(s.f1 == Approx(0.4));
    }
  }
  WHEN("two cuts fall in the same doorway") {
    THEN("only one of them matches (one-to-one)") { CHECK(scoreBoundaries({3, 4}, b, 0).matched == 1); }
  }
}

SCENARIO(
    "GIVEN two traversals of rooms 0,1,0 WHEN places are counted THEN per traversal counts and consistency "
    "follow") {
  const std::vector<int> rooms = {0, 0, 1, 1, 0, 0, 1, 1, 0, 0};
  const std::vector<std::int64_t> starts = {0, 5};
  const auto counts = placesPerTraversal({1, 3, 6, 9}, rooms, starts);
  REQUIRE(counts.size() == 2);
  CHECK(counts[0].places == 2);
  CHECK(counts[0].room_visits == 3);
  CHECK(counts[1].places == 2);
  CHECK(counts[1].room_visits == 3);
  const ConsistencyScore all = crossTraversalConsistency({1, 3, 6, 9}, rooms, starts);
  CHECK(all.eligible == 2);
  CHECK(all.consistent == 2);
  CHECK(all.rate == Approx(1.0));
  WHEN("room 1 yields no place in the second traversal") {
    const ConsistencyScore half = crossTraversalConsistency({1, 3, 9}, rooms, starts);
    THEN("half the rooms are consistent") {
      REQUIRE(half.rooms.size() == 2);
      CHECK(half.rooms[1].places == std::vector<int>{1, 0});
      CHECK(half.rate == Approx(0.5));
    }
  }
  CHECK(traversalOf(4, starts) == 0);
  CHECK(traversalOf(5, starts) == 1);
}

SCENARIO(
    "GIVEN six places on four nodes over three rooms WHEN the topology is scored THEN merges, splits and "
    "closures are counted") {
  // nodes 0,1,2,0,1,3; rooms 0,1,2,0,2,1: place 3 closes correctly on node 0, place 4 closes wrongly on
  // node 1 (room 2, node 1 so far only room 1), place 5 opens node 3 in room 1 seen before: missed.
  const TopologyScore s = scoreTopology({0, 1, 2, 0, 1, 3}, {0, 1, 2, 0, 2, 1});
  CHECK(s.nodes == 4);
  CHECK(s.rooms == 3);
  CHECK(s.one_to_one == 1);    // node 0 <-> room 0
  CHECK(s.merged_nodes == 1);  // node 1 spans rooms 1 and 2
  CHECK(s.split_rooms == 2);   // room 1 on nodes 1 and 3; room 2 on nodes 2 and 1
  CHECK(s.loop_closures == 2);
  CHECK(s.wrong_loop_closures == 1);
  CHECK(s.missed_loop_closures == 1);
  CHECK_THROWS_AS(scoreTopology({0}, {}), std::invalid_argument);
}

SCENARIO(
    "GIVEN values with ties WHEN the majority is taken THEN the smallest most frequent value >= 0 wins") {
  CHECK(majority({2, 1, 2, 1, -1, -1, -1}) == 1);
  CHECK(majority({-1}) == -1);
  CHECK(majority({3, 3, 1}) == 3);
}

namespace {

/// Two laps of a 30 m straight corridor walked east (0.1 m per frame, heading 0), 300 frames each; a third
/// stretch walks it back west (heading pi).
std::vector<GroundPose> twoLapsAndBack() {
  std::vector<GroundPose> poses;
  for (int lap = 0; lap < 2; ++lap)
    for (int i = 0; i < 300; ++i) poses.push_back(GroundPose{0.1 * i, 1.0, 0.0});
  for (int i = 0; i < 300; ++i) poses.push_back(GroundPose{30.0 - 0.1 * i, 1.0, 3.141592653589793});
  return poses;
}

}  // namespace

SCENARIO("GIVEN two laps cut into places WHEN revisits are scored by pose THEN right, missed and wrong closures are counted") {
  const std::vector<GroundPose> poses = twoLapsAndBack();
  // Lap 1: places 0-2 (10 m each); lap 2: places 3-5 over the same stretches; the way back: place 6.
  const auto places = [](std::vector<int> nodes) {
    std::vector<PlaceSpan> spans;
    for (int p = 0; p < 7; ++p) spans.push_back(PlaceSpan{100 * p, 100 * p + 99, nodes[static_cast<std::size_t>(p)]});
    return spans;
  };
  GIVEN("lap 2 on lap 1's nodes but its last place on a new node, and the way back new") {
    const PlaceRevisitScore s = scorePlaceRevisits(places({0, 1, 2, 0, 1, 3, 4}), poses);
    CHECK(s.places == 7);
    CHECK(s.revisits == 3);  // places 3-5; the way back looks the other way (heading pi): no revisit
    CHECK(s.closed_right == 2);
    CHECK(s.missed == 1);
    CHECK(s.wrong_closures == 0);
    CHECK(s.merged_with_previous == 0);
  }
  GIVEN("lap 2's first place on the node of lap 1's second, the way back on node 0") {
    const PlaceRevisitScore s = scorePlaceRevisits(places({0, 1, 2, 1, 1, 2, 0}), poses);
    CHECK(s.revisits == 3);
    CHECK(s.closed_right == 2);          // place 4 on node 1 (place 1), place 5 on node 2
    CHECK(s.wrong_closures == 2);        // place 3 on node 1 (it revisits place 0); place 6 revisits nothing
    CHECK(s.merged_with_previous == 0);  // place 4 stays on node 1 and revisits place 1 there: right
  }
  GIVEN("a place left on the previous place's node that it does not revisit") {
    const PlaceRevisitScore s = scorePlaceRevisits(places({0, 1, 2, 0, 0, 2, 3}), poses);
    CHECK(s.closed_right == 2);
    CHECK(s.merged_with_previous == 1);  // place 4 (revisits place 1) stays on node 0
  }
  GIVEN("a tolerance too tight for the half-frame offset of the second lap") {
    std::vector<GroundPose> shifted = poses;
    for (std::size_t f = 300; f < 600; ++f) shifted[f].y += 0.5;  // lap 2 half a metre to the side
    CHECK(scorePlaceRevisits(places({0, 1, 2, 0, 1, 2, 3}), shifted, 0.4).revisits == 0);
    CHECK(scorePlaceRevisits(places({0, 1, 2, 0, 1, 2, 3}), shifted, 1.0).closed_right == 3);
  }
  CHECK_THROWS_AS(scorePlaceRevisits({PlaceSpan{0, 900, 0}}, poses), std::invalid_argument);
  CHECK_THROWS_AS(scorePlaceRevisits({}, poses, 0.0), std::invalid_argument);
}

SCENARIO("GIVEN a real set's loop-closure truth WHEN revisits are scored by it THEN places are judged by its frame pairs") {
  // 60 frames: two laps of 30 (frame 30 + i shows what frame i shows, and its neighbours within 1).
  LoopClosureMatrix m;
  m.size = 60;
  m.same.assign(60 * 60, 0);
  for (int i = 0; i < 30; ++i)
    for (int d = -1; d <= 1; ++d)
      if (i + d >= 0 && i + d < 30) {
        m.same[static_cast<std::size_t>((30 + i) * 60 + i + d)] = 1;
        m.same[static_cast<std::size_t>((i + d) * 60 + 30 + i)] = 1;
      }
  const auto places = [](std::vector<int> nodes) {  // six places of 10 frames
    std::vector<PlaceSpan> spans;
    for (int p = 0; p < 6; ++p) spans.push_back(PlaceSpan{10 * p, 10 * p + 9, nodes[static_cast<std::size_t>(p)]});
    return spans;
  };
  const PlaceRevisitScore right = scorePlaceRevisits(places({0, 1, 2, 0, 1, 2}), m);
  CHECK(right.by_pose == false);
  CHECK(right.revisits == 3);
  CHECK(right.closed_right == 3);
  const PlaceRevisitScore new_nodes = scorePlaceRevisits(places({0, 1, 2, 3, 4, 5}), m);
  CHECK(new_nodes.missed == 3);
  CHECK(new_nodes.closed_right == 0);
  const PlaceRevisitScore swapped = scorePlaceRevisits(places({0, 1, 2, 1, 0, 2}), m);
  CHECK(swapped.closed_right == 1);
  CHECK(swapped.wrong_closures == 2);
  // A first lap alone has nothing to revisit, and a node reused there is a wrong closure.
  CHECK(scorePlaceRevisits(places({0, 1, 0, 3, 4, 5}), m).wrong_closures == 1);
  CHECK_THROWS_AS(scorePlaceRevisits({PlaceSpan{0, 60, 0}}, m), std::invalid_argument);
}

SCENARIO("GIVEN room labels only WHEN revisits are scored by them THEN a place on another room's node is a wrong "
         "closure") {
  // Four places of 10 frames: rooms 0, 1, then 0 again, then 2 (a floor never seen before).
  const std::vector<int> rooms = [] {
    std::vector<int> r;
    for (int room : {0, 1, 0, 2})
      for (int i = 0; i < 10; ++i) r.push_back(room);
    return r;
  }();
  const auto places = [](std::vector<int> nodes) {
    std::vector<PlaceSpan> spans;
    for (int p = 0; p < 4; ++p) spans.push_back(PlaceSpan{10 * p, 10 * p + 9, nodes[static_cast<std::size_t>(p)]});
    return spans;
  };
  const PlaceRevisitScore right = scorePlaceRevisits(places({0, 1, 0, 2}), rooms);
  CHECK(right.by_pose == false);
  CHECK(right.by_rooms == true);
  CHECK(right.revisits == 1);
  CHECK(right.closed_right == 1);
  CHECK(right.wrong_closures == 0);
  const PlaceRevisitScore merged_floors = scorePlaceRevisits(places({0, 1, 2, 0}), rooms);
  CHECK(merged_floors.missed == 1);          // place 2 back in room 0 on a new node
  CHECK(merged_floors.wrong_closures == 1);  // place 3 (room 2) on place 0's node (room 0)
  // Unknown labels show nothing: no revisit, and a reused node is a wrong closure.
  const PlaceRevisitScore unknown = scorePlaceRevisits(places({0, 1, 0, 2}), std::vector<int>(40, -1));
  CHECK(unknown.revisits == 0);
  CHECK(unknown.wrong_closures == 1);
}

SCENARIO("GIVEN published frame matches WHEN they are judged by pose THEN near matches facing alike are right") {
  std::vector<GroundPose> poses;
  for (int i = 0; i < 10; ++i) poses.push_back(GroundPose{1.0 * i, 0.0, 0.0});
  poses.push_back(GroundPose{0.5, 0.0, 0.0});                  // frame 10: back near frame 0
  poses.push_back(GroundPose{5.0, 0.0, 3.141592653589793});    // frame 11: at frame 5, facing the other way
  poses.push_back(GroundPose{});                                // frame 12: pose unknown
  std::vector<std::int64_t> match(13, -1);
  match[10] = 0;   // right (0.5 m)
  match[11] = 5;   // wrong: turned round
  match[12] = 3;   // not counted: unknown pose
  match[9] = 2;    // wrong: 7 m away
  const FrameMatchPoseScore s = scoreFrameMatchesByPose(match, poses);
  CHECK(s.matches == 3);
  CHECK(s.right == 1);
  CHECK(s.wrong == 2);
  CHECK(scoreFrameMatchesByPose(match, poses, 8.0, 1.0).right == 2);
  CHECK_THROWS_AS(scoreFrameMatchesByPose(std::vector<std::int64_t>(3, -1), poses), std::invalid_argument);
}
