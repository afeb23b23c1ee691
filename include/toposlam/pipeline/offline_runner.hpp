// The offline runner of `toposlam map` and `toposlam segment` (and of the end-to-end tests): the daemon's
// own stage adapters (VpackFingerprintStage or any FingerprintStage, FiedlerSegmentationStage,
// ParticleFilterTopologyStage), driven on the caller's thread, one frame after the other, each filter
// step run to its end before the next frame. So what the offline commands evaluate is what toposlamd
// runs (thesis chapters 3-5).
//
// Several traversals (sources) are processed one after another: beginTraversal() starts a fresh
// segmentation window and clock, the filter and the sequence evidence carry on. Frames and places are
// numbered from 0 over all traversals, in stream order (the run folder's numbering, docs/run-folder.md);
// the frame number is the sequence number the stages see. The three steps (fingerprint, segment,
// mapPlace) are separate calls so the caller can time each one; no clocks, threads or files here.
// Deterministic: the filter's seed decides everything. Not thread-safe.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/pipeline/stages.hpp"
#include "toposlam/segmentation/segmentation_run.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

/// One filter step: a kept place (run numbering) and the filter's estimate right after it.
struct MappedPlace {
  SegmentedPlace place;  ///< without its representative fingerprint (the filter keeps what it needs)
  TopologyEstimate estimate;
};

class OfflineRunner {
 public:
  /// The stages must outlive the runner. `topology` may already hold observations (a resumed map); null:
  /// segmentation only (`toposlam segment`), mapPlace() does nothing.
  OfflineRunner(FingerprintStage& fingerprint, FiedlerSegmentationStage& segmentation,
                ParticleFilterTopologyStage* topology = nullptr);

  /// Starts the next traversal (a fresh segmentation window); the first one starts implicitly. An open
  /// traversal is finished first (its last place is mapped).
  void beginTraversal();

  /// Step 1: the fingerprint of one frame (`grey`: the camera's own grey of it, or empty; Frame::grey).
  /// Throws std::invalid_argument for images the extractor refuses.
  std::shared_ptr<const Fingerprint> fingerprint(const cv::Mat& image, const cv::Mat& grey = cv::Mat());

  /// Step 2: segments the next frame, taken at `source_time_s` (the frame's own timestamp; the stage cuts
  /// out steps back, and looks motion samples given to it up at this time). A place closed by this frame,
  /// kept or dropped, is returned in the step, numbered in run order; a kept one must then be given to
  /// mapPlace() before the next frame.
  SegmenterStep segment(double source_time_s, const std::string& name, std::shared_ptr<const Fingerprint> fingerprint);

  /// Step 3: one filter step, run to its end, with the kept place just returned by segment() or
  /// finishTraversal(). Dropped places, and any place without a topology stage, give std::nullopt.
  std::optional<MappedPlace> mapPlace(const SegmentedPlace& place);

  /// End of the current traversal: closes its last place and returns it (map it with mapPlace()).
  std::optional<SegmentedPlace> finishTraversal();

  /// All three steps for one frame, and the flush: for callers that need no timing.
  void process(const cv::Mat& image, double source_time_s, const std::string& name = "");
  void finish();

  /// Frames and places of every traversal so far, run numbering (representatives not kept).
  const SegmentationRun& run() const { return run_; }
  /// Every frame's per-frame answer (the sequence detector's match, as toposlamd publishes it in place_t),
  /// in run numbering; match_frame -1 without one. Empty matches when the detector is off.
  const std::vector<RevisitEstimate>& revisits() const { return revisits_; }
  /// The filter steps of this run, in order.
  const std::vector<MappedPlace>& steps() const { return steps_; }
  /// Node of every kept place of this run in the filter's most probable topology (call between steps;
  /// empty without a topology stage).
  std::vector<std::int64_t> placeNodes() const;
  /// Filter observations that came before this run (a resumed map).
  int earlierObservations() const { return first_observation_; }
  int traversals() const { return traversal_count_; }
  /// Localisation only (the topology stage localises, ParticleFilterTopologyStage::startLocalizing): every
  /// frame's answer as toposlamd publishes it in place_t (node -1: not a known node), in run numbering.
  struct FrameNode {
    int node = -1;
    double probability = 0.0;
  };
  const std::vector<FrameNode>& frameNodes() const { return frame_nodes_; }

 private:
  void record(const SegmentedPlace& place);
  /// Localisation only: the frame's answer, after its place's step as on toposlamd's topology thread.
  void observe(const Fingerprint& fingerprint);

  FingerprintStage& fingerprint_;
  FiedlerSegmentationStage& segmentation_;
  ParticleFilterTopologyStage* topology_;
  int first_observation_ = 0;
  int traversal_count_ = 0;
  bool open_ = false;                  ///< a traversal is open (frames given since its start)
  std::optional<ClosedPlace> pending_;  ///< the kept place the segmentation stage closed last, for mapPlace()
  SegmentationRun run_;
  std::vector<RevisitEstimate> revisits_;
  std::vector<MappedPlace> steps_;
  std::vector<FrameNode> frame_nodes_;
  std::vector<std::int64_t> localized_place_nodes_;  ///< localisation only: per kept place of this run
  std::shared_ptr<const Fingerprint> unobserved_;     ///< localisation only: waits for its place's step
};

}  // namespace toposlam
