// A whole run folder against labels, a pairs CSV and bad truth: the numbers are worked out by hand from
// the fixture in eval_fixture.hpp.
#include <catch2/catch.hpp>

#include <sstream>

#include "eval_fixture.hpp"
#include "toposlam/eval/evaluation.hpp"
#include "toposlam/run_folder/json_reader.hpp"

using namespace toposlam;
using namespace toposlam::eval;
using namespace toposlam::eval::testing;
using Catch::Matchers::Contains;

SCENARIO(
    "GIVEN the fixture map run and its labels WHEN evaluated THEN every table holds the hand-computed "
    "numbers") {
  const auto dir = writeFixtureRun("labels");
  const RunData run = loadRun(dir.string());
  CHECK(run.traversal_starts == std::vector<std::int64_t>{0});
  const Truth truth = loadTruth((dir / "labels.csv").string());
  REQUIRE(truth.kind == Truth::Kind::Labels);
  const EvalResult r = evaluate(run, truth, EvalOptions{});
  CHECK(r.frames == 10);
  CHECK(r.places == 3);
  CHECK(r.min_gap == 0);

  REQUIRE(r.localisation);
  // 9 frames with a room: p = 1 (frames 0-2), 0.95 (4, 5), 0.6 (6-9); all on the node of their room.
  CHECK((*r.localisation)[0].images == 9);
  CHECK((*r.localisation)[1].images == 9);
  CHECK((*r.localisation)[2].images == 5);
  CHECK((*r.localisation)[4].precision == Approx(1.0));

  REQUIRE(r.loop_closure);
  // Room 0 visited at frames 0-2 and 6-9: 12 positive pairs, all predicted at p = 0.6.
  CHECK(r.loop_closure->positives == 12);
  CHECK(r.loop_closure->predicted == 12);
  CHECK(r.loop_closure->recall_at_full_precision == Approx(1.0));

  REQUIRE(r.boundaries);
  // Truth: doorway [3, 4] and [6, 6]; cuts at 3 and 6.
  CHECK(r.boundaries->truth == 2);
  CHECK(r.boundaries->predicted == 2);
  CHECK(r.boundaries->f1 == Approx(1.0));
  REQUIRE(r.places_per_traversal);
  CHECK((*r.places_per_traversal)[0].places == 3);
  CHECK((*r.places_per_traversal)[0].room_visits == 3);

  REQUIRE(r.topology);
  CHECK(r.topology->nodes == 2);
  CHECK(r.topology->one_to_one == 2);
  CHECK(r.topology->loop_closures == 1);
  CHECK(r.topology->wrong_loop_closures == 0);
  CHECK(r.best_topology_probability == std::vector<double>{1.0, 0.95, 0.7});

  WHEN("written as eval.json and read back") {
    std::ostringstream json;
    writeEvalJson(json, r);
    const JsonValue v = parseJson(json.str(), "eval.json");
    THEN("the numbers survive") {
      CHECK(v.at("loop_closure").at("recall_at_100_precision").asNumber() == Approx(1.0));
      CHECK(v.at("segmentation").at("f1").asNumber() == Approx(1.0));
      CHECK(v.at("topology").at("nodes").asNumber() == 2);
      CHECK(v.at("localisation").asArray().size() == 5);
    }
  }
  WHEN("formatted as text and HTML") {
    const std::string text = formatEvalText(r);
    const std::string html = formatEvalHtml(r);
    THEN("the tables are there") {
      CHECK_THAT(text, Contains("recall at 100% precision"));
      CHECK_THAT(text, Contains("100.00%"));
      CHECK_THAT(html, Contains("<table class=\"eval\">"));
    }
  }
  WHEN("split into two traversals") {
    EvalOptions two;
    two.traversals = 2;
    const EvalResult r2 = evaluate(run, truth, two);
    THEN("places are counted per half") {
      CHECK(r2.traversals == 2);
      REQUIRE(r2.places_per_traversal->size() == 2);
      CHECK((*r2.places_per_traversal)[0].places == 2);  // representatives 1 and 4 < 5
      CHECK((*r2.places_per_traversal)[1].places == 1);
    }
  }
}

SCENARIO(
    "GIVEN a pairs CSV naming frames WHEN evaluated with a gap of 2 frames THEN names resolve through "
    "frames.csv") {
  const auto dir = writeFixtureRun("pairs");
  writeText(dir / "pairs.csv", "query_image,matching_images\ng.png,a.png b.png\n");
  EvalOptions options;
  options.min_gap = 2;
  const EvalResult r = evaluate(loadRun(dir.string()), loadTruth((dir / "pairs.csv").string()), options);
  REQUIRE(r.loop_closure);
  // Node 0 is visited at frames 0-2 and again at 6-9: 12 cross pairs, all more than 2 frames apart; 2 are
  // true. (9,6) is more than 2 frames apart too but lies within the second visit: no loop closure.
  CHECK(r.loop_closure->positives == 2);
  CHECK(r.loop_closure->predicted == 12);
  CHECK(r.loop_closure->recall_at_full_precision == Approx(0.0));
  CHECK(r.loop_closure->points.back().precision == Approx(2.0 / 12.0));
  CHECK_FALSE(r.localisation);
  CHECK_FALSE(r.notes.empty());
}

SCENARIO(
    "GIVEN ground truth that does not fit the run WHEN evaluated THEN the error says what does not fit") {
  const auto dir = writeFixtureRun("misfit");
  const RunData run = loadRun(dir.string());
  writeText(dir / "short_labels.csv", "frame,time,room\n0,0,0\n");
  CHECK_THROWS_WITH(evaluate(run, loadTruth((dir / "short_labels.csv").string()), {}),
                    Contains("has 1 frames but"));
  writeText(dir / "pairs.csv", "query,matches\nzzz.png,a.png\n");
  CHECK_THROWS_WITH(evaluate(run, loadTruth((dir / "pairs.csv").string()), {}),
                    Contains("pairs.csv:2: frame 'zzz.png' is not in"));
  CHECK_THROWS_WITH(evaluate(run, loadTruth(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples_GT.bmp"), {}),
                    Contains("loop-closure matrix is 84x84 but"));
  CHECK_THROWS_WITH(loadRun((dir / "nope").string()), Contains("not a run folder"));
  const auto empty = scratchDir("empty-run");
  CHECK_THROWS_WITH(loadRun(empty.string()), Contains("frames.csv: missing"));
}

SCENARIO(
    "GIVEN labels with a traversal column WHEN evaluated THEN the traversals come from the labels, not an "
    "even split") {
  // A stop-and-go route: traversal 0 is frames 0-7 (a pause makes it long), traversal 1 frames 8-9; an even
  // split would start traversal 1 at frame 5.
  const auto dir = writeFixtureRun("traversal-column");
  writeText(dir / "labels_traversal.csv",
            "frame,time,room,x,y,heading,traversal\n0,0,0,0,0,0,0\n1,1,0,0,0,0,0\n2,2,0,0,0,0,0\n"
            "3,3,-1,0,0,0,0\n4,4,1,0,0,0,0\n5,5,1,0,0,0,0\n6,6,0,0,0,0,0\n7,7,0,0,0,0,0\n8,8,0,0,0,0,1\n"
            "9,9,0,0,0,0,1\n");
  const RunData run = loadRun(dir.string());
  const Truth truth = loadTruth((dir / "labels_traversal.csv").string());
  CHECK(truth.traversal_starts == std::vector<std::int64_t>{0, 8});
  const EvalResult r = evaluate(run, truth, EvalOptions{});
  CHECK(r.traversals == 2);
  CHECK(r.traversal_starts == std::vector<std::int64_t>{0, 8});
  REQUIRE(r.places_per_traversal);
  CHECK((*r.places_per_traversal)[0].places == 3);  // representatives 1, 4, 7 (an even split: 2 and 1)
  CHECK((*r.places_per_traversal)[1].places == 0);
  WHEN("--traversals 3 asks for an even split") {
    EvalOptions even;
    even.traversals = 3;
    const EvalResult r2 = evaluate(run, truth, even);
    THEN("the labels still decide and a note says the option was ignored") {
      CHECK(r2.traversal_starts == std::vector<std::int64_t>{0, 8});
      REQUIRE_FALSE(r2.notes.empty());
      CHECK_THAT(r2.notes.back(), Contains("--traversals 3 ignored"));
    }
  }
  WHEN("the old labels.csv without the column is evaluated with --traversals 2") {
    const Truth old = loadTruth((dir / "labels.csv").string());
    CHECK(old.traversal_starts.empty());
    CHECK(old.labels[9].traversal == -1);
    EvalOptions even;
    even.traversals = 2;
    const EvalResult r3 = evaluate(run, old, even);
    THEN("the frames are split evenly as before") {
      CHECK(r3.traversal_starts == std::vector<std::int64_t>{0, 5});
    }
  }
  WHEN("two labels files are given, the first with two traversals in it") {
    writeText(dir / "first.csv", "frame,room,traversal\n0,0,0\n1,0,0\n2,0,1\n3,-1,1\n4,1,1\n");
    writeText(dir / "second.csv", "frame,room\n0,1\n1,0\n2,0\n3,0\n4,0\n");
    const Truth both =
        loadTruth(std::vector<std::string>{(dir / "first.csv").string(), (dir / "second.csv").string()});
    THEN("each file and each traversal inside one starts a traversal") {
      CHECK(both.traversal_starts == std::vector<std::int64_t>{0, 2, 5});
      CHECK(both.labels[9].traversal == 2);
      CHECK(evaluate(run, both, EvalOptions{}).traversals == 3);
    }
  }
}

SCENARIO(
    "GIVEN a labels file whose traversal column goes backwards WHEN loaded THEN the error names the line") {
  const auto dir = scratchDir("traversal-backwards");
  writeText(dir / "labels.csv", "frame,room,traversal\n0,0,0\n1,0,1\n2,0,0\n");
  CHECK_THROWS_WITH(loadTruth((dir / "labels.csv").string()),
                    Contains("labels.csv:4: traversal 0 after traversal 1"));
  writeText(dir / "negative.csv", "frame,room,traversal\n0,0,-1\n");
  CHECK_THROWS_WITH(loadTruth((dir / "negative.csv").string()), Contains("negative.csv:2: traversal -1"));
}

SCENARIO(
    "GIVEN a damaged run folder WHEN loaded or evaluated THEN it is refused with the file, line and frames") {
  const auto dir = writeFixtureRun("damaged");
  WHEN("a place starts at a negative frame") {
    writeText(dir / "places.csv", "place,first,last,representative,keypoints,node\n0,-3,2,1,50,0\n");
    THEN("places.csv names the line") {
      CHECK_THROWS_WITH(loadRun(dir.string()),
                        Contains("places.csv:2: need 0 <= first <= representative <= last"));
    }
  }
  WHEN("a place runs past the last frame of frames.csv") {
    writeText(dir / "places.csv",
              "place,first,last,representative,keypoints,node\n0,0,2,1,50,0\n7,6,14,12,9,0\n");
    THEN("the error names the place and the frame count") {
      CHECK_THROWS_WITH(loadRun(dir.string()),
                        Contains("places.csv:3: place 7 spans frames 6..14 but frames.csv has 10 frames"));
    }
  }
  WHEN("a dropped place does") {
    writeText(dir / "dropped_places.csv",
              "place,first,last,representative,keypoints,node\n9,10,10,10,1,-1\n");
    THEN("dropped_places.csv is named") {
      CHECK_THROWS_WITH(loadRun(dir.string()), Contains("dropped_places.csv:2: place 9 spans frames 10..10"));
    }
  }
  WHEN("a run built in memory has a representative out of range") {
    RunData run = loadRun(dir.string());
    run.places[1].representative = -5;
    THEN("evaluate refuses it instead of reading outside the labels") {
      CHECK_THROWS_WITH(
          evaluate(run, loadTruth((dir / "labels.csv").string()), {}),
          Contains("place 1 (frames 3..5, representative -5) does not lie inside the 10 frames"));
    }
  }
}
