// The daemon's stages (FiedlerSegmentationStage -> ParticleFilterTopologyStage) and `toposlam map`'s
// OfflineRunner on the same frames, with the filter's sequence evidence on (docs/topology.md): the same
// places, the same evidence and the same nodes. Two laps of three blocks of near-identical frames.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

#include "../segmentation/fake_similarity.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/pipeline/clock.hpp"
#include "toposlam/pipeline/offline_runner.hpp"

using namespace toposlam;

namespace {
constexpr int kLap = 120, kBlock = 40;
// Frame ids 0..239; the second lap (120..239) retraces the first block by block.
double twoLaps(int a, int b) {
  const int pa = a % kLap, pb = b % kLap;
  return pa / kBlock == pb / kBlock ? 0.9 + 0.05 * std::sin(0.7 * pa + 1.3 * pb) : 0.05;
}
FiedlerSegmenterConfig segmentation() {
  FiedlerSegmenterConfig c;
  c.window = 20;
  return c;
}
TopologyFilterConfig topology() {
  TopologyFilterConfig c;
  c.particles = 100;
  c.likelihood = LikelihoodModel::Relative;
  return c;
}
SequenceEvidenceConfig evidenceOn() {
  SequenceEvidenceConfig e;
  e.weight = 0.99;
  return e;
}
double timeOf(int f) { return 0.2 * f; }  // 5 fps: keyframes once a second, a lap of 24 s
}  // namespace

TEST_CASE("GIVEN sequence evidence on WHEN the daemon's stages and the offline runner see the same frames THEN "
          "places, evidence and nodes are the same",
          "[pipeline][evidence]") {
  const test::TableSimilarity similarity(twoLaps);

  // The daemon's stages, the filter step run to its end after every place.
  FiedlerSegmentationStage segmenter(segmentation(), similarity, 600, {}, evidenceOn());
  ManualClock clock;
  ParticleFilterTopologyStage filter(topology(), similarity, clock, {64, 3});
  std::vector<ClosedPlace> stage_places;
  const auto mapOnline = [&](const ClosedPlace& place) {
    stage_places.push_back(place);
    filter.enqueuePlace(place);
    while (!filter.idle()) filter.advance(1e9);
  };
  for (int f = 0; f < 2 * kLap; ++f) {
    const SegmentationStep step = segmenter.process(f, timeOf(f), timeOf(f), test::fakeFingerprint(f), cv::Mat());
    if (step.closed) mapOnline(*step.closed);
  }
  if (auto last = segmenter.finish()) mapOnline(*last);

  // The offline runner, on stages of its own.
  VpackFingerprintStage fingerprints(VpackConfig{}, nullptr);  // unused: fingerprints are made up
  FiedlerSegmentationStage offline_segmenter(segmentation(), similarity, 1, {}, evidenceOn());
  ParticleFilterTopologyStage offline_filter(topology(), similarity, clock, {64, 3});
  OfflineRunner runner(fingerprints, offline_segmenter, &offline_filter);
  for (int f = 0; f < 2 * kLap; ++f) {
    const SegmenterStep step = runner.segment(timeOf(f), "", test::fakeFingerprint(f));
    if (step.closed_place) runner.mapPlace(*step.closed_place);
  }
  if (auto last = runner.finishTraversal()) runner.mapPlace(*last);

  const SegmentationRun& run = runner.run();
  REQUIRE(run.places.size() == stage_places.size());
  REQUIRE(stage_places.size() == 6u);  // three blocks a lap
  for (std::size_t p = 0; p < stage_places.size(); ++p) {
    CHECK(stage_places[p].first_frame == run.places[p].first_frame);
    CHECK(stage_places[p].last_frame == run.places[p].last_frame);
    CHECK(stage_places[p].evidence.size() == p);
  }
  // The second lap's places carry evidence on their first-lap twins, from its second place on (in the
  // first, the evidence D still builds up, by (1 - decay) z a keyframe, over most of its 8 keyframes).
  for (std::size_t p = 4; p < 6; ++p) CHECK(stage_places[p].evidence[p - 3] >= 0.99 * 0.8);
  const std::vector<std::int64_t> offline_nodes = runner.placeNodes();
  const TopologySnapshot online = filter.topology();
  std::vector<std::int64_t> online_nodes(stage_places.size(), -1);
  for (const TopologyNode& node : online.nodes)
    for (const int place : node.places) online_nodes[static_cast<std::size_t>(place)] = node.id;
  CHECK(online_nodes == offline_nodes);
  CHECK(offline_nodes == std::vector<std::int64_t>{0, 1, 2, 0, 1, 2});
}
