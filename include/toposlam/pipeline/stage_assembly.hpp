// The one assembly of the stages (docs/architecture.md, "One assembly"): the fingerprint, the similarity,
// the segmentation and the topology stage, built in dependency order from the stages' settings (the
// config's sections of the same names; DaemonConfig is a StageSettings), a clock and, for the daemon, the
// fingerprint's worker pool. toposlamd runs them on its pipeline threads, `toposlam map` and `segment` on
// one thread through OfflineRunner: so what the offline commands evaluate is what the daemon runs.
// The frame loops share one per-frame error policy (frame_failures.hpp). No threads, no I/O.
#pragma once

#include <cstdint>
#include <memory>

#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/pipeline/clock.hpp"
#include "toposlam/pipeline/pipeline.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"
#include "toposlam/topology/sequence_loop_closures.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

class WorkerPool;

/// Every stage's settings: the sections fingerprint.*, similarity.*, segmentation.* and topology.* of the
/// config (their keys land in these members; config_keys.hpp).
struct StageSettings {
  VpackConfig fingerprint;
  FingerprintStageConfig fingerprint_stage;  ///< fingerprint.workers, pipeline.thumbnail_width
  NgramSimilarityConfig similarity;
  FiedlerSegmenterConfig segmentation;
  SegmentationStageConfig segmentation_stage;  ///< segmentation.motion.*
  TopologyFilterConfig topology;
  TopologyStageConfig topology_stage;          ///< topology.slice_items, topology.alternatives
  SequenceEvidenceConfig sequence_evidence;    ///< topology.sequence_evidence.* (docs/topology.md)
};

/// The localisation-only mode's settings (map.localize.*, with the map's similarity.*).
NodeLocalizerConfig nodeLocalizerConfig(const NgramSimilarityConfig& similarity, const MapLocalizeConfig& localize);

/// What the run publishes besides the places: the daemon's place events carry thumbnails, the offline
/// commands keep none.
enum class Thumbnails { Kept, None };

/// The stages of one run. `pool` (may be null: the caller's thread alone) and `clock` must outlive it.
/// The topology stage starts with a new filter; a saved map replaces it (topology().adoptMap).
class StageAssembly {
 public:
  StageAssembly(const StageSettings& settings, const Clock& clock, WorkerPool* pool, Thumbnails thumbnails);

  VpackFingerprintStage& fingerprint() { return *fingerprint_; }
  const NgramSimilarity& similarity() const { return *similarity_; }
  FiedlerSegmentationStage& segmentation() { return *segmentation_; }
  ParticleFilterTopologyStage& topology() { return *topology_; }

 private:
  std::unique_ptr<VpackFingerprintStage> fingerprint_;
  std::unique_ptr<NgramSimilarity> similarity_;
  std::unique_ptr<FiedlerSegmentationStage> segmentation_;
  std::unique_ptr<ParticleFilterTopologyStage> topology_;
};

}  // namespace toposlam
