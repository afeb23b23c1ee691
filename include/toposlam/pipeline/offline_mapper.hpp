// Offline topological SLAM, the per-frame pipeline of `toposlam map` and of the end-to-end tests:
// fingerprint a frame (VPACK), segment it (FiedlerSegmenter, one fresh window per traversal), and step
// the topology particle filter with every kept place's representative (thesis chapters 3-5).
//
// Several traversals (sources) are processed one after another: beginTraversal() starts a fresh
// segmentation window, the filter carries on. Frames and places are numbered from 0 over all
// traversals, in stream order (the run folder's numbering, docs/run-folder.md). The three steps
// (fingerprint, segment, mapPlace) are separate calls so the caller can time each one; no clocks,
// threads or files here. Deterministic: the filter's seed decides everything. Not thread-safe.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "toposlam/segmentation/offline_segmentation.hpp"
#include "toposlam/topology/sequence_loop_closures.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

/// One filter step: a kept place (run numbering) and the filter's estimate right after it.
struct MappedPlace {
  SegmentedPlace place;  ///< its representative fingerprint is released after the step
  TopologyEstimate estimate;
};

class OfflineMapper {
 public:
  /// `extractor`, `similarity` and `filter` must outlive the mapper; `filter` may already hold
  /// observations (a resumed map). Throws std::invalid_argument on a bad segmentation config.
  OfflineMapper(const VpackExtractor& extractor, const SimilarityMeasure& similarity,
                const FiedlerSegmenterConfig& config, TopologyParticleFilter& filter);

  /// From now on, every filter step also gets the sequence evidence of the place's frames
  /// (PlaceSequenceEvidence; docs/topology.md). Call before the first frame; weight 0 turns it off.
  /// Throws std::invalid_argument on a bad config.
  void useSequenceEvidence(const SequenceEvidenceConfig& config);

  /// Starts the next traversal (a fresh segmentation window); the first one starts implicitly. An open
  /// traversal is finished first (its last place is mapped).
  void beginTraversal();

  /// Step 1: the VPACK fingerprint of one frame. Throws std::invalid_argument for images the
  /// extractor refuses.
  std::shared_ptr<const Fingerprint> fingerprint(const cv::Mat& image) const;

  /// Step 2: segments the next frame. A place closed by this frame is returned in the step, numbered in
  /// run order; a kept one must then be given to mapPlace().
  /// `motion` as in OfflineSegmentation::segment.
  SegmenterStep segment(double time_s, const std::string& name, std::shared_ptr<const Fingerprint> fingerprint,
                        const MotionState& motion = {});

  /// Step 3: one filter step with a kept place's representative (run numbering, as returned by
  /// segment() or finishTraversal()). Dropped places are ignored (returns std::nullopt).
  std::optional<MappedPlace> mapPlace(const SegmentedPlace& place);

  /// End of the current traversal: closes its last place and returns it (map it with mapPlace()).
  std::optional<SegmentedPlace> finishTraversal();

  /// All three steps for one frame, and the flush: for callers that need no timing.
  void process(const cv::Mat& image, double time_s, const std::string& name = "");
  void finish();

  /// Frames and places of every traversal so far, run numbering (the open traversal included).
  SegmentationRun run() const;
  /// The filter steps of this run, in order.
  const std::vector<MappedPlace>& steps() const { return steps_; }
  /// Node of every kept place of this run in the filter's most probable topology (call between steps).
  std::vector<std::int64_t> placeNodes() const;
  /// Filter observations that came before this run (a resumed map).
  int earlierObservations() const { return first_observation_; }
  int traversals() const { return traversal_count_; }

 private:
  SegmentedPlace toRunNumbering(SegmentedPlace place) const;
  void appendTraversal();

  const VpackExtractor& extractor_;
  const SimilarityMeasure& similarity_;
  FiedlerSegmenterConfig config_;
  TopologyParticleFilter& filter_;
  int first_observation_ = 0;
  int traversal_count_ = 0;
  std::unique_ptr<OfflineSegmentation> current_;  ///< the open traversal, null between traversals
  std::unique_ptr<PlaceSequenceEvidence> evidence_;  ///< null: the representatives alone
  SegmentationRun finished_;                      ///< traversals already closed, run numbering
  std::vector<MappedPlace> steps_;
};

/// Appends one traversal's segmentation to the run of all traversals, renumbering frames and places
/// (representative fingerprints are not copied).
void appendSegmentationRun(SegmentationRun& all, const SegmentationRun& part);

}  // namespace toposlam
