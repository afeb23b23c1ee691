// The JSON reader and the run-folder / ground-truth loaders: valid files, and clear errors naming file and
// line.
#include <catch2/catch.hpp>

#include <cmath>

#include "eval_fixture.hpp"
#include "toposlam/eval/json_reader.hpp"
#include "toposlam/eval/run_files.hpp"

using namespace toposlam::eval;
using namespace toposlam::eval::testing;
using Catch::Matchers::Contains;

SCENARIO("GIVEN a JSON document WHEN parsed THEN values, escapes and nesting come back") {
  const JsonValue v = parseJson(R"({"a": [1, -2.5e1, true, null], "s": "x\"\u00e9\n", "o": {"k": NaN}})");
  REQUIRE(v.isObject());
  const auto& a = v.at("a").asArray();
  REQUIRE(a.size() == 4);
  CHECK(a[0].asNumber() == 1.0);
  CHECK(a[1].asNumber() == -25.0);
  CHECK(a[2].asBool());
  CHECK(a[3].isNull());
  CHECK(v.at("s").asString() == "x\"\xc3\xa9\n");
  CHECK(std::isnan(v.at("o").at("k").asNumber()));
  CHECK(v.find("missing") == nullptr);
  CHECK_THROWS_WITH(v.at("missing"), Contains("missing key 'missing'"));
  CHECK_THROWS_WITH(v.at("s").asNumber("s"), Contains("s: expected a number"));
}

SCENARIO("GIVEN malformed JSON WHEN parsed THEN the error names the source, line and column") {
  CHECK_THROWS_WITH(parseJson("{\n  \"a\": [1, 2,\n}", "t.json"),
                    Contains("t.json:3:1: unexpected character '}'"));
  CHECK_THROWS_WITH(parseJson("{\"a\" 1}", "t.json"), Contains("t.json:1:6: expected ':'"));
  CHECK_THROWS_WITH(parseJson("[1, 2", "t.json"), Contains("unterminated array"));
  CHECK_THROWS_WITH(parseJson("\"abc", "t.json"), Contains("unterminated string"));
  CHECK_THROWS_WITH(parseJson("{} x", "t.json"), Contains("unexpected text after"));
  CHECK_THROWS_WITH(parseJson("", "t.json"), Contains("unexpected end of input"));
  CHECK_THROWS_WITH(parseJson(std::string(500, '['), "t.json"), Contains("nested too deeply"));
  CHECK_THROWS_WITH(readJsonFile("/nonexistent/topology.json"),
                    Contains("/nonexistent/topology.json: cannot open"));
}

SCENARIO("GIVEN the fixture run folder WHEN its files are loaded THEN every field is read") {
  const auto dir = writeFixtureRun("load");
  const auto frames = loadFrames((dir / "frames.csv").string());
  REQUIRE(frames.size() == 10);
  CHECK(std::isnan(frames[0].lambda2));
  CHECK(frames[3].lambda2 == Approx(0.4));
  CHECK(frames[3].name == "d.png");
  CHECK(frames[4].place == 1);
  CHECK(frames[4].node == 1);
  const auto places = loadPlaces((dir / "places.csv").string());
  REQUIRE(places.size() == 3);
  CHECK(places[2].first == 6);
  CHECK(places[2].representative == 7);
  CHECK(places[2].keypoints == 70);
  const TopologyFile topo = loadTopology((dir / "topology.json").string());
  CHECK(topo.probability == Approx(0.7));
  CHECK(topo.particles == 500);
  REQUIRE(topo.nodes.size() == 2);
  CHECK(topo.nodes[0].places == std::vector<int>{0, 2});
  CHECK(topo.nodes[0].representative_frames == std::vector<std::int64_t>{1, 7});
  REQUIRE(topo.history.size() == 3);
  CHECK(topo.history[2].probability == Approx(0.6));
  CHECK(topo.history[2].best_topology_probability == Approx(0.7));
  CHECK(topo.edges.size() == 2);
  const auto labels = loadLabels((dir / "labels.csv").string());
  REQUIRE(labels.size() == 10);
  CHECK(labels[3].room == -1);
  CHECK(labels[4].room == 1);
  CHECK(labels[4].x == 0.0);  // the fixture has a pose (all zeros)
  const auto timing = loadTiming((dir / "timing.csv").string());
  REQUIRE(timing.size() == 3);
  CHECK(timing[2].filter_ms == Approx(5.0));
}

SCENARIO("GIVEN malformed run files WHEN loaded THEN the error names the file and the line") {
  const auto dir = scratchDir("bad");
  writeText(dir / "frames.csv", "frame,time,name,lambda2,place,node\n0,0,a,,0,0\n1,x,b,,0,0\n");
  CHECK_THROWS_WITH(loadFrames((dir / "frames.csv").string()),
                    Contains("frames.csv:3: column 'time': 'x' is not a number"));
  writeText(dir / "labels.csv", "frame,time,x\n0,0,0\n");
  CHECK_THROWS_WITH(loadLabels((dir / "labels.csv").string()),
                    Contains("labels.csv:1: missing column 'room'"));
  writeText(dir / "labels-pose.csv", "frame,room,x,y\n0,1,0,0\n");
  CHECK_THROWS_WITH(loadLabels((dir / "labels-pose.csv").string()),
                    Contains("labels-pose.csv:1: a pose needs all of the columns x, y and heading (found x y )"));
  writeText(dir / "labels-pose2.csv", "frame,room,x,y,heading\n0,1,0,0,north\n");
  CHECK_THROWS_WITH(loadLabels((dir / "labels-pose2.csv").string()),
                    Contains("labels-pose2.csv:2: column 'heading': 'north' is not a number"));
  writeText(dir / "labels2.csv", "frame,room\n0,1\n2,1\n");
  CHECK_THROWS_WITH(loadLabels((dir / "labels2.csv").string()),
                    Contains("labels2.csv:3: frame 2 out of order, expected 1"));
  writeText(dir / "places.csv", "place,first,last,representative\n0,5,3,4\n");
  CHECK_THROWS_WITH(loadPlaces((dir / "places.csv").string()),
                    Contains("places.csv:2: need 0 <= first <= representative <= last"));
  writeText(dir / "topology.json", "{\"nodes\": []}");
  CHECK_THROWS_WITH(loadTopology((dir / "topology.json").string()),
                    Contains("topology.json: missing key 'probability'"));
  writeText(dir / "topology2.json", "{\"probability\": 1, \"nodes\": [{\"id\": \"x\", \"places\": []}]}");
  CHECK_THROWS_WITH(loadTopology((dir / "topology2.json").string()),
                    Contains("nodes[].id: expected a number"));
  writeText(dir / "empty.csv", "");
  CHECK_THROWS_WITH(loadFrames((dir / "empty.csv").string()), Contains("empty.csv:1: empty file"));
  CHECK_THROWS_WITH(loadFrames((dir / "none.csv").string()), Contains("none.csv: cannot open"));
  writeText(dir / "gt.bmp", "not an image");
  CHECK_THROWS_WITH(loadLoopClosureImage((dir / "gt.bmp").string()),
                    Contains("gt.bmp: cannot read as an image"));
}

SCENARIO(
    "GIVEN the bundled samples_GT.bmp and samples_GT_pairs.csv WHEN loaded THEN both hold the same 228 loop "
    "closures") {
  const std::string samples = TOPOSLAM_SAMPLES_DIR;
  const LoopClosureMatrix m = loadLoopClosureImage(samples + "/samples_GT.bmp");
  REQUIRE(m.size == 84);
  CHECK(m.at(40, 0));  // 41.jpg revisits 1.jpg
  CHECK(m.at(0, 40));  // symmetric after loading
  CHECK_FALSE(m.at(1, 0));
  CHECK(m.at(80, 38));  // 81.jpg - 39.jpg
  int marked = 0;
  for (int i = 0; i < 84; ++i) {
    for (int j = 0; j < i; ++j) marked += m.at(i, j) ? 1 : 0;
  }
  CHECK(marked == 228);
  const auto pairs = loadLoopClosurePairs(samples + "/samples_GT_pairs.csv");
  REQUIRE(pairs.size() == 228);
  CHECK(pairs[0].query == "41.jpg");
  CHECK(pairs[0].match == "1.jpg");
  CHECK(pairs[0].line == 2);
}

SCENARIO("GIVEN labels with the camera's pose WHEN loaded THEN x, y and heading are read") {
  const auto dir = scratchDir("pose");
  writeText(dir / "labels.csv", "frame,time,room,x,y,heading,traversal\n0,0.0,0,1.5,-2.25,3.1,0\n1,0.2,-1,1.6,-2.25,3.0,0\n");
  const auto labels = loadLabels((dir / "labels.csv").string());
  REQUIRE(labels.size() == 2);
  CHECK(labels[0].x == 1.5);
  CHECK(labels[0].y == -2.25);
  CHECK(labels[1].heading == 3.0);
  CHECK(labels[1].room == -1);
}
