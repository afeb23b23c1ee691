// Test fixture for the end-to-end mapping tests: a route's fingerprints (simulated worlds with room
// labels, or the 84 real sample frames with their loop-closure matrix), computed once per process, and
// the topology and segmentation scores of one OfflineRunner run over them (the daemon's stages) (src/eval's measures).
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "toposlam/eval/metrics.hpp"
#include "toposlam/eval/ground_truth.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/pipeline/clock.hpp"
#include "toposlam/pipeline/offline_runner.hpp"
#include "toposlam/sim/simulator.hpp"

namespace toposlam::testing {

/// A route ready to map: fingerprints in stream order and what is known about them.
struct MappingRoute {
  std::string name;
  std::vector<std::shared_ptr<const Fingerprint>> fingerprints;
  std::vector<double> times_s;
  std::vector<int> rooms;                      ///< simulated: room per frame (-1 doorway); real: empty
  std::vector<std::int64_t> traversal_starts;  ///< first frame of each traversal (for the scores)
  bool separate_sources = false;  ///< each traversal a source of its own (fresh window), as `map A B`
  eval::LoopClosureMatrix loop_closures;       ///< real frames: the ground-truth matrix
};

/// The simulator's route (default camera: 320x240 at 5 fps), fingerprinted with default VPACK.
inline MappingRoute simulatedRoute(const std::string& world, const std::string& route) {
  sim::SimConfig config;
  config.world = world;
  config.route = route;
  sim::Simulator simulator(config);
  const VpackExtractor extractor;
  MappingRoute r;
  r.name = world + "-" + route;
  int traversal = -1;
  while (auto frame = simulator.next()) {
    if (frame->truth.traversal != traversal) {
      traversal = frame->truth.traversal;
      r.traversal_starts.push_back(static_cast<std::int64_t>(r.rooms.size()));
    }
    r.fingerprints.push_back(std::make_shared<const Fingerprint>(extractor.extract(frame->image)));
    r.times_s.push_back(frame->truth.time_s);
    r.rooms.push_back(frame->truth.room);
  }
  return r;
}

/// The 84 bundled sample frames (1 Hz keyframes, times 0, 1, 2, ... s as `images:` gives them).
inline MappingRoute sampleRoute() {
  const VpackExtractor extractor;
  MappingRoute r;
  r.name = "samples";
  r.traversal_starts = {0};
  for (int i = 1; i <= 84; ++i) {
    const std::string path = std::string(TOPOSLAM_SAMPLES_DIR) + "/samples/" + std::to_string(i) + ".jpg";
    const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
    if (image.empty()) throw std::runtime_error("cannot read " + path);
    r.fingerprints.push_back(std::make_shared<const Fingerprint>(extractor.extract(image)));
    r.times_s.push_back(static_cast<double>(i - 1));
  }
  r.loop_closures = eval::loadLoopClosureImage(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples_GT.bmp");
  return r;
}

/// Memoises NgramSimilarity per ordered fingerprint pair (the tuning sweeps revisit the same pairs).
class CachedSimilarity : public SimilarityMeasure {
 public:
  double similarity(const Fingerprint& reference, const Fingerprint& query) const override {
    const std::lock_guard<std::mutex> lock(mutex_);
    const auto key = std::make_pair(&reference, &query);
    if (auto it = cache_.find(key); it != cache_.end()) return it->second;
    const double value = inner_.similarity(reference, query);
    cache_.emplace(key, value);
    return value;
  }

 private:
  NgramSimilarity inner_;
  mutable std::mutex mutex_;
  mutable std::map<std::pair<const Fingerprint*, const Fingerprint*>, double> cache_;
};

/// What one mapping run gives, with the evaluation's measures (docs/evaluation.md).
struct MappingScore {
  int kept = 0, dropped = 0;
  std::vector<std::int64_t> cuts;       ///< first frame of every place after a valley
  eval::BoundaryScore boundaries_5;     ///< simulated routes only
  eval::BoundaryScore boundaries_15;
  eval::TopologyScore topology;         ///< simulated routes only
  std::vector<int> place_node, place_room, place_traversal;
  std::vector<SegmentedPlace> places;  ///< kept, run numbering
  double closure_precision = 0.0, closure_recall = 0.0;  ///< frame pairs, every prediction accepted
  double best_probability = 0.0;
};

/// Maps `route` with `config` and the default filter (500 particles, alpha 15) seeded with `seed`.
inline MappingScore mapRoute(const MappingRoute& route, const FiedlerSegmenterConfig& config,
                             const SimilarityMeasure& similarity, std::uint64_t seed = 1) {
  VpackFingerprintStage fingerprints(VpackConfig{}, nullptr);  // unused: the route is fingerprinted
  FiedlerSegmentationStage segmentation(config, similarity, 1);
  TopologyFilterConfig filter_config;
  filter_config.seed = seed;
  const ManualClock clock;
  ParticleFilterTopologyStage topology(filter_config, similarity, clock, TopologyStageConfig{});
  OfflineRunner runner(fingerprints, segmentation, &topology);
  for (std::size_t f = 0; f < route.fingerprints.size(); ++f) {
    const auto frame = static_cast<std::int64_t>(f);
    if (route.separate_sources && frame > 0 && std::count(route.traversal_starts.begin(), route.traversal_starts.end(), frame) > 0)
      runner.beginTraversal();
    const SegmenterStep step = runner.segment(route.times_s[f], "", route.fingerprints[f]);
    if (step.closed_place) runner.mapPlace(*step.closed_place);
  }
  runner.finish();

  MappingScore score;
  const SegmentationRun& run = runner.run();
  const std::vector<std::int64_t> nodes = runner.placeNodes();
  score.kept = static_cast<int>(run.places.size());
  score.places = run.places;
  score.dropped = static_cast<int>(run.dropped_places.size());
  score.best_probability = topology.filter().estimate(0).best.probability;
  for (const auto* list : {&run.places, &run.dropped_places}) {
    for (const SegmentedPlace& p : *list) {
      if (p.first_frame > 0 &&
          std::count(route.traversal_starts.begin(), route.traversal_starts.end(), p.first_frame) == 0)
        score.cuts.push_back(p.first_frame);
    }
  }
  std::sort(score.cuts.begin(), score.cuts.end());

  std::vector<int> node_of_frame(route.fingerprints.size(), -1);
  for (const SegmentedPlace& p : run.places) {
    for (std::int64_t f = p.first_frame; f <= p.last_frame; ++f)
      node_of_frame[static_cast<std::size_t>(f)] = static_cast<int>(nodes[static_cast<std::size_t>(p.index)]);
  }
  for (const SegmentedPlace& p : run.places)
    score.place_node.push_back(static_cast<int>(nodes[static_cast<std::size_t>(p.index)]));
  eval::LoopClosureTruth truth;
  if (!route.rooms.empty()) {
    truth = eval::truthFromRooms(route.rooms, 0);
    const auto intervals = eval::roomBoundaries(route.rooms, route.traversal_starts);
    score.boundaries_5 = eval::scoreBoundaries(score.cuts, intervals, 5);
    score.boundaries_15 = eval::scoreBoundaries(score.cuts, intervals, 15);
    for (const SegmentedPlace& p : run.places) {
      int room = route.rooms[static_cast<std::size_t>(p.representative_frame)];
      if (room < 0) {
        room = eval::majority(std::vector<int>(route.rooms.begin() + p.first_frame,
                                               route.rooms.begin() + p.last_frame + 1));
      }
      score.place_room.push_back(room);
      score.place_traversal.push_back(eval::traversalOf(p.representative_frame, route.traversal_starts));
    }
    score.topology = eval::scoreTopology(score.place_node, score.place_room);
  } else {
    truth = eval::truthFromMatrix(route.loop_closures, 25);  // `toposlam eval`'s default gap for a matrix
  }
  const eval::PrCurve curve =
      eval::precisionRecall(truth, eval::pairsFromAssignments(node_of_frame, std::vector<double>(node_of_frame.size(), 1.0)));
  if (!curve.points.empty()) {
    score.closure_precision = curve.points.back().precision;
    score.closure_recall = curve.points.back().recall;
  }
  return score;
}

}  // namespace toposlam::testing
