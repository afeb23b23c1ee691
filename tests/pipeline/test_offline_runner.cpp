// OfflineRunner (`toposlam map`'s runner of the daemon's stages) on hand-made similarities: two traversals (sources) of the
// same three blocks. Checks the run numbering across traversals, one filter step per kept place, and
// that the second traversal's places land on the first traversal's nodes.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "segmentation/fake_similarity.hpp"
#include "toposlam/pipeline/clock.hpp"
#include "toposlam/pipeline/offline_runner.hpp"

using namespace toposlam;
using toposlam::test::fakeFingerprint;
using toposlam::test::TableSimilarity;

SCENARIO("OfflineRunner maps two traversals of three blocks onto three nodes", "[segmentation][runner]") {
  GIVEN("two sources of 120 frames each, blocks of 40 frames that match their twin of the other source") {
    auto block = [](int frame) { return (frame % 120) / 40; };
    TableSimilarity similarity([&](int a, int b) {
      if (block(a) != block(b)) return 0.05;
      return 0.9 + 0.05 * std::sin(0.7 * a + 1.3 * b);
    });
    VpackFingerprintStage fingerprints(VpackConfig{}, nullptr);  // unused: fingerprints are made up
    FiedlerSegmentationStage segmentation(test::thesisConfig(), similarity, 1);
    const ManualClock clock;
    ParticleFilterTopologyStage topology(TopologyFilterConfig{}, similarity, clock, TopologyStageConfig{});
    OfflineRunner runner(fingerprints, segmentation, &topology);
    std::vector<std::int64_t> closed_frames;
    for (int source = 0; source < 2; ++source) {
      runner.beginTraversal();
      for (int i = 0; i < 120; ++i) {
        const SegmenterStep step = runner.segment(0.2 * i, "", fakeFingerprint(120 * source + i));
        CHECK(step.frame == 120 * source + i);
        if (step.closed_place) {
          closed_frames.push_back(step.closed_place->first_frame);
          runner.mapPlace(*step.closed_place);
        }
      }
      if (auto last = runner.finishTraversal()) {
        closed_frames.push_back(last->first_frame);
        runner.mapPlace(*last);
      }
    }
    const SegmentationRun& run = runner.run();
    THEN("frames and places are numbered over both traversals, each traversal cut at its block borders") {
      REQUIRE(run.frames.size() == 240);
      CHECK(run.frames[239].frame == 239);
      REQUIRE(run.places.size() == 6);
      CHECK(closed_frames == std::vector<std::int64_t>{0, 40, 80, 120, 160, 200});
      for (std::size_t p = 0; p < 6; ++p) {
        CHECK(run.places[p].index == static_cast<std::int64_t>(p));
        CHECK(run.places[p].first_frame == static_cast<std::int64_t>(40 * p));
      }
      CHECK(run.frames[130].place == 3);
      CHECK(runner.traversals() == 2);
    }
    THEN("one filter step per kept place, and the second traversal closes the loop onto the same nodes") {
      REQUIRE(runner.steps().size() == 6);
      CHECK(runner.steps()[3].place.first_frame == 120);
      CHECK(topology.observations() == 6);
      const std::vector<std::int64_t> nodes = runner.placeNodes();
      CHECK(nodes == std::vector<std::int64_t>{0, 1, 2, 0, 1, 2});
    }
  }
}
