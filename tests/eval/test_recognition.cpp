// Place recognition measures on hand-made similarity matrices with answers worked out by hand.
#include <catch2/catch.hpp>

#include <cmath>

#include "toposlam/eval/recognition.hpp"

using namespace toposlam::eval;

SCENARIO("GIVEN a query/reference truth WHEN scored THEN AUC, top-1 and recall at 100 % precision are exact") {
  // 3 queries x 3 references. Query 0 matches reference 0, query 1 matches reference 1, query 2 has no
  // match. Similarities: q0 best at r0 (0.9, right), q1 best at r2 (0.6, wrong; its match scores 0.5),
  // q2 best at r1 (0.7, wrong: it has no match).
  const RecognitionTruth truth = crossTruth(3, 3, {1, 0, 0, 0, 1, 0, 0, 0, 0});
  const std::vector<float> s = {0.9f, 0.1f, 0.2f, 0.3f, 0.5f, 0.6f, 0.4f, 0.7f, 0.1f};
  const RecognitionScore r = scoreRecognition(s, truth);
  CHECK(r.queries == 3);
  CHECK(r.queries_with_match == 2);
  CHECK(r.positive_pairs == 2);
  CHECK(r.negative_pairs == 7);
  // Positives 0.9 and 0.5; negatives 0.1 0.2 0.3 0.6 0.4 0.7 0.1: 0.9 beats all 7, 0.5 beats 5 of 7.
  CHECK(r.auc == Approx(12.0 / 14.0));
  CHECK(r.top1 == Approx(0.5));
  CHECK(r.top1_correct == 1);
  // Detections by score: q0 0.9 right, q2 0.7 wrong, q1 0.6 wrong: recall 1/2 before the first mistake.
  CHECK(r.recall_at_full_precision == Approx(0.5));
  CHECK(r.threshold_at_full_precision == Approx(0.9f));
  REQUIRE(r.curve.size() == 3);
  CHECK(r.curve[1].precision == Approx(0.5));
  CHECK(r.best_reference == std::vector<int>{0, 2, 1});
}

SCENARIO("GIVEN tied similarities WHEN scored THEN ties count one half in the AUC and go to the earlier reference") {
  const RecognitionTruth truth = crossTruth(1, 2, {0, 1});
  const RecognitionScore r = scoreRecognition({0.5f, 0.5f}, truth);
  CHECK(r.auc == Approx(0.5));
  CHECK(r.best_reference == std::vector<int>{0});
  CHECK(r.top1 == Approx(0.0));
  CHECK(r.recall_at_full_precision == 0.0);
}

SCENARIO("GIVEN one sequence WHEN its truth is built THEN only frames at least min_gap back are candidates") {
  LoopClosureMatrix m;
  m.size = 5;
  m.same.assign(25, 0);
  m.same[4 * 5 + 0] = 1;  // frame 4 revisits frame 0
  m.same[0 * 5 + 4] = 1;
  m.same[3 * 5 + 2] = 1;  // too close to count
  const RecognitionTruth t = sequenceTruthFromMatrix(m, 2);
  CHECK(t.at(4, 0) == 1);
  CHECK(t.at(4, 2) == 0);
  CHECK(t.at(4, 3) == -1);
  CHECK(t.at(3, 2) == -1);
  CHECK(t.at(0, 4) == -1);  // the future is no candidate
  CHECK(t.at(2, 0) == 0);
  CHECK_THROWS_AS(sequenceTruthFromMatrix(m, 0), std::invalid_argument);
}

SCENARIO("GIVEN rooms per frame WHEN the sequence truth is built THEN revisits are positives and the same visit is no candidate") {
  // rooms: 0 0 1 -1 0 : frame 4 revisits room 0 (frames 0, 1), frame 1 is in the same visit as frame 0.
  const RecognitionTruth t = sequenceTruthFromRooms({0, 0, 1, -1, 0}, 1);
  CHECK(t.at(4, 0) == 1);
  CHECK(t.at(4, 1) == 1);
  CHECK(t.at(4, 2) == 0);
  CHECK(t.at(4, 3) == -1);
  CHECK(t.at(1, 0) == -1);
  CHECK(t.at(2, 0) == 0);
}

SCENARIO("GIVEN frame paths WHEN a pairs file's name is resolved THEN a path suffix at a folder border matches") {
  const std::vector<std::string> paths = {"/d/ref/0000001.jpg", "/d/query/0000001.jpg", "/d/x10.jpg"};
  CHECK(resolveFrameName("ref/0000001.jpg", paths) == 0);
  CHECK(resolveFrameName("query/0000001.jpg", paths) == 1);
  CHECK(resolveFrameName("10.jpg", paths) == -1);  // "x10.jpg" is another name
  CHECK_THROWS_AS(resolveFrameName("0000001.jpg", paths), std::invalid_argument);
}
