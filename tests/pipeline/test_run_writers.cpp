// OfflineRunner's bookkeeping (segmentation only, as `toposlam segment`) and the run folder made from its rows
// (src/run_folder, docs/run-folder.md), with fake
// fingerprints and a table similarity: frame rows get their place once it closes, dropped places are
// -1, CSV headers and columns are exact, the lambda2 plot marks each valley-closed border.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "segmentation/fake_similarity.hpp"
#include "toposlam/pipeline/offline_runner.hpp"
#include "toposlam/run_folder/run_folder.hpp"

using toposlam::test::fakeFingerprint;
using toposlam::test::TableSimilarity;
using toposlam::test::thesisConfig;

namespace {

std::vector<std::string> linesOf(const std::filesystem::path& path) {
  std::vector<std::string> lines;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::filesystem::path scratchFolder(const std::string& name) {
  const auto dir = std::filesystem::path(TOPOSLAM_BINARY_DIR) / "test-scratch" / "pipeline" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace

TEST_CASE(
    "GIVEN three blocks, the middle one keypoint-poor WHEN run through OfflineRunner THEN the rows and "
    "CSV files follow docs/run-folder.md",
    "[segmentation][run]") {
  auto block = [](int f) { return f < 40 ? 0 : (f < 80 ? 1 : 2); };
  TableSimilarity similarity([&](int a, int b) { return block(a) == block(b) ? 0.9 : 0.05; });
  toposlam::VpackFingerprintStage fingerprint_stage(toposlam::VpackConfig{}, nullptr);  // unused: fingerprints are given
  toposlam::FiedlerSegmentationStage segmentation_stage(thesisConfig(), similarity, 1);
  toposlam::OfflineRunner pipeline(fingerprint_stage, segmentation_stage);
  for (int f = 0; f < 120; ++f) {
    std::string name = "f";
    name.append(std::to_string(f)).append(".png");
    pipeline.segment(0.5 * f, name, fakeFingerprint(f, block(f) == 1 ? 3 : 40));
  }
  THEN("before finish, the last block's frames have no place yet") {
    CHECK(pipeline.run().frames[100].place == -1);
    CHECK(pipeline.run().frames[10].place == 0);
  }
  REQUIRE(pipeline.finishTraversal().has_value());
  const toposlam::SegmentationRun& run = pipeline.run();
  REQUIRE(run.places.size() == 2);
  REQUIRE(run.dropped_places.size() == 1);
  CHECK(run.frames[10].place == 0);
  CHECK(run.frames[50].place == -1);
  CHECK(run.frames[50].in_dropped_place);
  CHECK(run.frames[100].place == 1);

  const auto dir = scratchFolder("run-writers");
  toposlam::writeFrames(dir, toposlam::frameRows(run, {7, 9}), toposlam::FrameColumns::Segmentation);
  toposlam::writePlaces(dir, toposlam::placeRows(run.places, {7, 9}));
  toposlam::writeDroppedPlaces(dir, toposlam::placeRows(run.dropped_places));
  const auto frames = linesOf(dir / "frames.csv");
  REQUIRE(frames.size() == 121);
  CHECK(frames[0] == "frame,time,name,lambda2,place,node");
  CHECK(frames[1] == "0,0.000000,f0.png,,0,7");  // one frame in the window: no lambda2 yet
  CHECK(frames[2] == "1,0.500000,f1.png,2.000000,0,7");
  CHECK(frames[71] == "70,35.000000,f70.png,1.041667,-1,-1");  // a full window inside block 1
  CHECK(frames[101].substr(frames[101].size() - 4) == ",1,9");
  const auto places = linesOf(dir / "places.csv");
  REQUIRE(places.size() == 3);
  CHECK(places[0] == "place,first,last,representative,keypoints,node,end");
  CHECK(places[1].rfind("0,0,39,", 0) == 0);
  CHECK(places[2].rfind("1,80,119,", 0) == 0);
  CHECK(places[1].substr(places[1].size() - 7) == ",valley");  // closed by the valley after block 0
  CHECK(places[2].substr(places[2].size() - 16) == ",40,9,stream_end");
  const auto dropped = linesOf(dir / "dropped_places.csv");
  REQUIRE(dropped.size() == 2);
  CHECK(dropped[1].rfind("0,40,79,", 0) == 0);
  CHECK(dropped[1].substr(dropped[1].size() - 12) == ",3,-1,valley");

  THEN("the lambda2 plot has one series and a dashed line at each of the two valley-closed borders") {
    const toposlam::SvgPlot plot = toposlam::lambda2Plot(run, {}, "test");
    REQUIRE(plot.series.size() == 1);
    CHECK(plot.series[0].y.size() == 120);
    CHECK(std::isnan(plot.series[0].y[0]));
    REQUIRE(plot.vertical_lines.size() == 2);
    CHECK(plot.vertical_lines[0].value == 39.5);
    CHECK(plot.vertical_lines[1].value == 79.5);
    CHECK(plot.horizontal_lines.at(0).value == 0.5);
  }
}

TEST_CASE(
    "GIVEN frame names with commas, quotes and line breaks WHEN frames.csv is written and read back by eval THEN "
    "every name and column survives",
    "[segmentation][run][reliability]") {
  toposlam::SegmentationRun run;
  const std::vector<std::string> names = {"plain.jpg", "a,b.jpg", "say \"hi\".jpg", "two\nlines.jpg", "cr\r\nlf.jpg",
                                          ",\",\n"};
  for (std::size_t f = 0; f < names.size(); ++f) {
    toposlam::SegmentationFrameRecord row;
    row.frame = static_cast<std::int64_t>(f);
    row.time_s = 0.25 * static_cast<double>(f);
    row.name = names[f];
    row.lambda2 = 0.5;
    row.place = 0;
    run.frames.push_back(row);
  }
  const auto dir = scratchFolder("frames-quoted-names");
  toposlam::writeFrames(dir, toposlam::frameRows(run, {3}), toposlam::FrameColumns::Segmentation);
  const std::vector<toposlam::FrameRecord> back = toposlam::loadFrames((dir / "frames.csv").string());
  REQUIRE(back.size() == names.size());
  for (std::size_t f = 0; f < names.size(); ++f) {
    INFO("frame " << f);
    CHECK(back[f].frame == static_cast<std::int64_t>(f));
    CHECK(back[f].name == names[f]);
    CHECK(back[f].time_s == Approx(0.25 * static_cast<double>(f)));
    CHECK(back[f].place == 0);
    CHECK(back[f].node == 3);
  }
}
