// NodeLocalizer (localisation only): the thesis' naive-Bayes localisation over a map's nodes, carried from
// frame to frame along the map's edges, on real frames of the bundled samples (a corridor loop driven
// twice): the frames of the first lap make the nodes, the second lap is localised in them.
#include <catch2/catch.hpp>

#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/node_localizer.hpp"

using namespace toposlam;

namespace {

Fingerprint sample(int number) {
  static const VpackExtractor extractor{VpackConfig{}};
  const cv::Mat image = cv::imread(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples/" + std::to_string(number) + ".jpg",
                                   cv::IMREAD_ANYCOLOR);
  REQUIRE_FALSE(image.empty());
  return extractor.extract(image);
}

/// Four nodes (ids 10, 11, 12, 13) of three consecutive first-lap frames each, in a chain 10 -> 11 -> 12 -> 13.
MapNodes chainOfFour() {
  MapNodes m;
  const int first[] = {1, 11, 21, 31};
  for (int n = 0; n < 4; ++n) {
    m.node_ids.push_back(10 + n);
    LabelledPlace node{std::to_string(10 + n), {}};
    for (int f = first[n]; f < first[n] + 3; ++f) node.references.push_back(sample(f));
    m.nodes.push_back(std::move(node));
  }
  m.successors = {{{1, 1.0}}, {{2, 1.0}}, {{3, 1.0}}, {}};
  return m;
}

}  // namespace

SCENARIO("GIVEN a map of four nodes WHEN the frames of one node arrive THEN that node is the answer, by its id") {
  NodeLocalizer localizer(NodeLocalizerConfig{}, chainOfFour());
  REQUIRE(localizer.nodeCount() == 4);
  NodeFix fix;
  for (int f = 1; f <= 3; ++f) fix = localizer.update(sample(f), 2);
  CHECK(fix.node == 10);
  CHECK(fix.best_node == 10);
  CHECK(fix.probability > 0.9);
  REQUIRE(fix.alternatives.size() == 2);
  CHECK(fix.alternatives[0].probability <= fix.probability);
  CHECK(fix.alternatives[0].node != 10);
  // One fingerprint alone, without the history: a frame of the third node.
  CHECK(localizer.localizeOnce(sample(22)).best_node == 12);
}

SCENARIO("GIVEN the stream's places WHEN frames arrive THEN the share of staying follows their mean length") {
  NodeLocalizer localizer(NodeLocalizerConfig{}, chainOfFour());
  localizer.update(sample(1));
  CHECK(localizer.stayProbability() == Approx(0.5));  // one frame seen: floored at a place of 2 frames
  localizer.update(sample(2));
  localizer.update(sample(3));
  localizer.update(sample(4));
  CHECK(localizer.stayProbability() == Approx(0.75));  // no place closed yet: the 4 frames seen so far
  localizer.placeClosed(10);
  localizer.placeClosed(30);
  localizer.update(sample(5));
  CHECK(localizer.stayProbability() == Approx(1.0 - 1.0 / 20.0));  // mean place: 20 frames
}

SCENARIO("GIVEN a belief under min_probability WHEN a frame is answered THEN it is not a known node") {
  NodeLocalizerConfig config;
  config.min_probability = 1.0;
  NodeLocalizer localizer(config, chainOfFour());
  const NodeFix fix = localizer.update(sample(40));
  CHECK(fix.node == -1);
  CHECK(fix.best_node >= 10);
  CHECK(fix.probability < 1.0);
}

SCENARIO("GIVEN the robot in the first node WHEN a frame of the chain's far end arrives THEN the graph doubts it") {
  // Along the edges the robot cannot be at node 13 one frame after node 10; only the jump weight takes it
  // there, so the far end gets less belief than the frame alone gives it.
  NodeLocalizer localizer(NodeLocalizerConfig{}, chainOfFour());
  for (int f = 1; f <= 3; ++f) localizer.update(sample(f));
  const NodeFix alone = localizer.localizeOnce(sample(32));
  CHECK(alone.best_node == 13);
  const NodeFix fix = localizer.update(sample(32));
  CHECK(fix.probability < alone.probability);
  // With no way off the edges at all (jump 0) the far end cannot be reached in one frame.
  NodeLocalizerConfig no_jump;
  no_jump.jump_weight = 0.0;
  NodeLocalizer strict(no_jump, chainOfFour());
  for (int f = 1; f <= 3; ++f) strict.update(sample(f));
  CHECK(strict.update(sample(32)).best_node != 13);
}

SCENARIO("GIVEN bad settings or no node WHEN a localiser is made THEN it is refused by what is wrong") {
  NodeLocalizerConfig bad;
  bad.min_probability = 1.5;
  CHECK_THROWS_WITH(NodeLocalizer(bad, chainOfFour()), Catch::Contains("min_probability"));
  bad = NodeLocalizerConfig{};
  bad.jump_weight = -1.0;
  CHECK_THROWS_WITH(NodeLocalizer(bad, chainOfFour()), Catch::Contains("jump_weight"));
  CHECK_THROWS_AS(NodeLocalizer(NodeLocalizerConfig{}, MapNodes{}), std::invalid_argument);
}
