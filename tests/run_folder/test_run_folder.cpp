// The run folder's format (src/run_folder): the JSON reader, the loaders (valid files, and clear errors naming
// file and line), and every writer's file read back by its loader.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "eval/eval_fixture.hpp"
#include "toposlam/run_folder/json_reader.hpp"
#include "toposlam/run_folder/run_folder.hpp"

using namespace toposlam;
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
  writeText(dir / "places-end.csv",
            "place,first,last,representative,keypoints,node,end\n0,0,3,1,50,0,valley\n1,4,6,5,50,1,vally\n");
  CHECK_THROWS_WITH(loadPlaces((dir / "places-end.csv").string()),
                    Contains("places-end.csv:3: end 'vally' is not one of valley, valley_at_doorway"));
  writeText(dir / "places-end2.csv",
            "place,first,last,representative,keypoints,node,end\n0,0,3,1,50,0,\n1,4,6,5,50,1,stream_end\n");
  const auto ends = loadPlaces((dir / "places-end2.csv").string());
  REQUIRE(ends.size() == 2);
  CHECK(ends[0].end.empty());
  CHECK(ends[1].end == "stream_end");
  writeText(dir / "topology.json", "{\"nodes\": []}");
  CHECK_THROWS_WITH(loadTopology((dir / "topology.json").string()),
                    Contains("topology.json: missing key 'probability'"));
  writeText(dir / "topology2.json", "{\"probability\": 1, \"nodes\": [{\"id\": \"x\", \"places\": []}]}");
  CHECK_THROWS_WITH(loadTopology((dir / "topology2.json").string()),
                    Contains("nodes[].id: expected a number"));
  writeText(dir / "empty.csv", "");
  CHECK_THROWS_WITH(loadFrames((dir / "empty.csv").string()), Contains("empty.csv:1: empty file"));
  CHECK_THROWS_WITH(loadFrames((dir / "none.csv").string()), Contains("none.csv: cannot open"));
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

namespace {

std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A map-like run folder written by the module's writers: names that need quoting, every optional column.
std::filesystem::path writeRoundTripRun(const std::string& name) {
  const auto dir = scratchDir(name);
  std::vector<FrameRecord> frames(6);
  const std::vector<std::string> names = {"plain.jpg", "a,b.jpg", "say \"hi\".jpg", "two\nlines.jpg", "cr\r\nlf.jpg",
                                          ",\",\n"};
  for (std::size_t f = 0; f < frames.size(); ++f) {
    frames[f].frame = static_cast<std::int64_t>(f);
    frames[f].time_s = 0.25 * static_cast<double>(f);
    frames[f].name = names[f];
    if (f > 0) frames[f].lambda2 = 0.125 * static_cast<double>(f);
    frames[f].place = f < 3 ? 0 : 1;
    frames[f].node = f < 3 ? 4 : 5;
    frames[f].node_probability = 0.75;
  }
  frames[4].match = 1;
  frames[4].match_score = 2.5;
  writeFrames(dir, frames, FrameColumns::WithLoopClosures);
  writePlaces(dir, {PlaceRecord{0, 0, 0, 2, 1, 40, 4, "doorway"}, PlaceRecord{1, 0, 3, 5, 4, 50, 5, "stream_end"}});
  writeDroppedPlaces(dir, {});
  TopologyFile topology;
  topology.probability = 0.5;
  topology.particles = 200;
  TopologyFile::Estimate& e = topology.estimate.emplace();
  e.current_node = 5;
  e.current_node_probability = 0.875;
  e.effective_sample_size = 150.5;
  e.distinct_topologies = 3;
  e.earlier_places = 2;
  e.alternatives.push_back(TopologyFile::Alternative{0.25, 3, 1});
  topology.nodes.push_back(TopologyFile::Node{4, {0}, {1}, {0, 1}});
  topology.nodes.push_back(TopologyFile::Node{5, {1}, {4}, {}});
  topology.edges.push_back(TopologyFile::Edge{4, 5, 1});
  TopologyFile::Step step;
  step.place = 1;
  step.node = 5;
  step.probability = 0.875;
  step.best_topology_probability = 0.5;
  step.effective_sample_size = 150.5;
  step.is_new = true;
  topology.history.push_back(step);
  writeTopology(dir, topology);
  writeTiming(dir, {TimingRow{0, 1.5, 0.25, 2.0}, TimingRow{1, 1.25, 0.5, std::nullopt}});
  writeSources(dir, {"images:/data/ref", "images:/data/query"});
  writeSettings(dir, {{"preset", "default"}, {"topology.seed", "1"}});
  return dir;
}

}  // namespace

SCENARIO("GIVEN a run folder made by the writers WHEN it is read back THEN every row and field is what was written",
         "[run_folder]") {
  const auto dir = writeRoundTripRun("round-trip");
  const RunData run = loadRun(dir.string());
  REQUIRE(run.frames.size() == 6);
  CHECK(run.has_frame_matches);
  CHECK(std::isnan(run.frames[0].lambda2));
  for (std::size_t f = 0; f < 6; ++f) {
    INFO("frame " << f);
    CHECK(run.frames[f].frame == static_cast<std::int64_t>(f));
    CHECK(run.frames[f].time_s == 0.25 * static_cast<double>(f));
    if (f > 0) CHECK(run.frames[f].lambda2 == 0.125 * static_cast<double>(f));
    CHECK(run.frames[f].place == (f < 3 ? 0 : 1));
    CHECK(run.frames[f].node == (f < 3 ? 4 : 5));
    CHECK(run.frames[f].node_probability == 0.75);
    CHECK(run.frames[f].match == (f == 4 ? 1 : -1));
    CHECK(run.frames[f].match_score == (f == 4 ? 2.5 : 0.0));
  }
  CHECK(run.frames[1].name == "a,b.jpg");
  CHECK(run.frames[2].name == "say \"hi\".jpg");
  CHECK(run.frames[3].name == "two\nlines.jpg");
  CHECK(run.frames[4].name == "cr\r\nlf.jpg");
  CHECK(run.frames[5].name == ",\",\n");
  REQUIRE(run.places.size() == 2);
  CHECK(run.places[1].place == 1);
  CHECK(run.places[1].first == 3);
  CHECK(run.places[1].last == 5);
  CHECK(run.places[1].representative == 4);
  CHECK(run.places[1].keypoints == 50);
  CHECK(run.places[1].node == 5);
  CHECK(run.places[1].line == 3);
  CHECK(run.places[0].end == "doorway");
  CHECK(run.places[1].end == "stream_end");
  CHECK(run.dropped_places.empty());
  REQUIRE(run.topology.has_value());
  const TopologyFile& t = *run.topology;
  CHECK(t.probability == 0.5);
  CHECK(t.particles == 200);
  REQUIRE(t.estimate.has_value());
  CHECK(t.estimate->current_node == 5);
  CHECK(t.estimate->current_node_probability == 0.875);
  CHECK(t.estimate->effective_sample_size == 150.5);
  CHECK(t.estimate->distinct_topologies == 3);
  CHECK(t.estimate->earlier_places == 2);
  REQUIRE(t.estimate->alternatives.size() == 1);
  CHECK(t.estimate->alternatives[0].probability == 0.25);
  CHECK(t.estimate->alternatives[0].nodes == 3);
  CHECK(t.estimate->alternatives[0].first_difference == 1);
  REQUIRE(t.nodes.size() == 2);
  CHECK(t.nodes[0].places == std::vector<int>{0});
  CHECK(t.nodes[0].representative_frames == std::vector<std::int64_t>{1});
  CHECK(t.nodes[0].earlier_places == std::vector<int>{0, 1});
  CHECK(t.nodes[1].earlier_places.empty());
  REQUIRE(t.edges.size() == 1);
  CHECK(t.edges[0].from == 4);
  CHECK(t.edges[0].to == 5);
  CHECK(t.edges[0].count == 1);
  REQUIRE(t.history.size() == 1);
  CHECK(t.history[0].place == 1);
  CHECK(t.history[0].node == 5);
  CHECK(t.history[0].probability == 0.875);
  CHECK(t.history[0].best_topology_probability == 0.5);
  CHECK(t.history[0].effective_sample_size == 150.5);
  CHECK(t.history[0].is_new == true);
  REQUIRE(run.timing.size() == 2);
  CHECK(run.timing[0].fingerprint_ms == 1.5);
  CHECK(run.timing[0].segment_ms == 0.25);
  CHECK(run.timing[0].filter_ms == 2.0);
  CHECK_FALSE(run.timing[1].filter_ms.has_value());
  CHECK(run.sources == std::vector<std::string>{"images:/data/ref", "images:/data/query"});
  REQUIRE(run.settings.size() == 2);
  CHECK(run.settings[1].first == "topology.seed");
  CHECK(run.settings[1].second == "1");

  THEN("the files are byte for byte what a second write of what was read gives") {
    const auto again = scratchDir("round-trip-again");
    writeFrames(again, run.frames, FrameColumns::WithLoopClosures);
    writePlaces(again, run.places);
    writeTopology(again, *run.topology);
    writeTiming(again, run.timing);
    for (const char* file : {run_files::kFrames, run_files::kPlaces, run_files::kTopology, run_files::kTiming}) {
      INFO(file);
      CHECK(readText(again / file) == readText(dir / file));
    }
  }
}

SCENARIO("GIVEN frames with node probabilities and no frame matches (a map's export) WHEN written and read THEN the "
         "probabilities come back and the folder has no match columns", "[run_folder]") {
  const auto dir = scratchDir("node-probability-columns");
  FrameRecord row;
  row.place = 0;
  row.node = 2;
  row.node_probability = 0.625;
  writeFrames(dir, {row}, FrameColumns::WithNodeProbability);
  CHECK(readText(dir / run_files::kFrames) == "frame,time,name,lambda2,place,node,node_probability\n0,0.000000,,,0,2,0.625000\n");
  const RunData run = loadRun(dir.string());
  REQUIRE(run.frames.size() == 1);
  CHECK(run.frames[0].node_probability == 0.625);
  CHECK_FALSE(run.has_frame_matches);
}

SCENARIO("GIVEN the segmentation columns and the simulator's labels WHEN written THEN the headers are exact and read back",
         "[run_folder]") {
  const auto dir = scratchDir("segmentation-columns");
  FrameRecord row;
  row.name = "0.png";
  row.place = 0;
  writeFrames(dir, {row}, FrameColumns::Segmentation);
  CHECK(readText(dir / run_files::kFrames) == "frame,time,name,lambda2,place,node\n0,0.000000,0.png,,0,-1\n");
  LabelRow label;
  label.frame = 0;
  label.time_s = 0.2;
  label.room = 3;
  label.x = 1.5;
  label.y = -2.25;
  label.heading = 3.14159;
  label.traversal = 0;
  writeText(dir / run_files::kLabels, labelsHeader() + labelsRow(label));
  CHECK(readText(dir / run_files::kLabels) == "frame,time,room,x,y,heading,traversal\n0,0.2000,3,1.5000,-2.2500,3.14159,0\n");
  const auto labels = loadLabels((dir / run_files::kLabels).string());
  REQUIRE(labels.size() == 1);
  CHECK(labels[0].room == 3);
  CHECK(labels[0].heading == 3.14159);
  CHECK(labels[0].traversal == 0);
}

SCENARIO("GIVEN a run folder whose files were cut short WHEN it is read THEN the error names the file and the line",
         "[run_folder][reliability]") {
  const auto dir = writeRoundTripRun("truncated");
  const std::string frames = readText(dir / run_files::kFrames);
  const std::string topology = readText(dir / run_files::kTopology);
  WHEN("frames.csv ends inside a row") {
    // The last row ("5,1.250000,...") cut after its time: the place column is missing.
    const std::size_t last_row = frames.rfind("\n5,");
    writeText(dir / run_files::kFrames, frames.substr(0, last_row + 12));
    CHECK_THROWS_WITH(loadRun(dir.string()), Contains("frames.csv:") && Contains(": column 'place' is empty"));
  }
  WHEN("frames.csv lost its last rows, so places.csv points past its end") {
    writeText(dir / run_files::kFrames, frames.substr(0, frames.find("\n3,") + 1));
    CHECK_THROWS_WITH(loadRun(dir.string()),
                      Contains("places.csv:3: place 1 spans frames 3..5 but frames.csv has 3 frames"));
  }
  WHEN("topology.json ends in the middle") {
    writeText(dir / run_files::kTopology, topology.substr(0, topology.size() / 2));
    CHECK_THROWS_WITH(loadRun(dir.string()), Contains("topology.json:") && Contains("unterminated"));
  }
  WHEN("frames.csv is empty (cut before its header)") {
    writeText(dir / run_files::kFrames, "");
    CHECK_THROWS_WITH(loadRun(dir.string()), Contains("frames.csv:1: empty file, expected a header line"));
  }
  WHEN("the folder has no frames.csv") {
    std::filesystem::remove(dir / run_files::kFrames);
    CHECK_THROWS_WITH(loadRun(dir.string()), Contains("frames.csv: missing"));
  }
}
