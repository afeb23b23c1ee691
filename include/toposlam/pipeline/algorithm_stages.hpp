// The real algorithms as pipeline stages: thin adapters from the stage interfaces (stages.hpp) to
// VpackExtractor, FiedlerSegmenter and TopologyParticleFilter (+ MapStore). They hold no threads; each
// is used by its one pipeline thread.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "toposlam/core/frame_timeline.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/frame_similarity_memo.hpp"
#include "toposlam/pipeline/clock.hpp"
#include "toposlam/pipeline/stages.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"
#include "toposlam/topology/map_store.hpp"
#include "toposlam/matching/node_localizer.hpp"
#include "toposlam/topology/sequence_loop_closures.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

class WorkerPool;

// The stage adapters' own settings, beside the algorithm configs they wrap (VpackConfig,
// FiedlerSegmenterConfig, TopologyFilterConfig). DaemonConfig holds one of each; the key table
// (config_keys.cpp) gives each member its key, default and range.

/// fingerprint.*: how the fingerprint stage runs VPACK, and the thumbnail it makes.
struct FingerprintStageConfig {
  int workers = 2;  ///< fingerprint.workers: WorkerPool threads incl. the fingerprint thread, 1 .. 64
  /// pipeline.thumbnail_width (its key from before the stage made thumbnails): the place-event thumbnail's
  /// width in pixels, 16 .. 1280; the height keeps the aspect.
  int thumbnail_width = 160;
};

/// segmentation.*: what the segmentation stage adds to the segmenter.
struct SegmentationStageConfig {
  MotionGateConfig motion;  ///< segmentation.motion.*: when TOPOSLAM_MOTION says the robot stands
};

/// topology.*: how the topology stage runs the filter.
struct TopologyStageConfig {
  int slice_items = 256;  ///< topology.slice_items: filter work items per advance() slice, 1 .. 1000000
  int alternatives = 3;   ///< topology.alternatives: other nodes published per frame, 0 .. 16
};

/// VPACK extraction, and the frame's thumbnail for the place events: the frame shrunk to
/// `thumbnail_width` pixels (never enlarged; the height keeps the aspect, at least 1) by pixel-area
/// averaging (cv::INTER_AREA). The per-subregion work runs on `pool` (borrowed; null = inline).
class VpackFingerprintStage final : public FingerprintStage {
 public:
  /// No thumbnail: the offline commands, which publish no place events.
  static constexpr int kNoThumbnail = 0;
  /// `thumbnail_width`: FingerprintStageConfig::thumbnail_width, or kNoThumbnail.
  VpackFingerprintStage(const VpackConfig& config, WorkerPool* pool, int thumbnail_width = kNoThumbnail)
      : extractor_(config, pool), thumbnail_width_(thumbnail_width) {}
  /// Throws std::invalid_argument for images the extractor refuses.
  FingerprintedFrame process(const cv::Mat& image, const cv::Mat& grey) override;

 private:
  VpackExtractor extractor_;
  int thumbnail_width_;
};

/// One robot motion sample for the segmentation stage (from TOPOSLAM_MOTION's motion_t).
struct MotionSample {
  double time_s = 0.0;                ///< pipeline clock (CLOCK_MONOTONIC seconds: motion_t.utime / 1e6)
  double distance_increment_m = 0.0;  ///< travelled since the previous sample
  double speed_mps = 0.0;
  double turn_rate_rps = 0.0;  ///< yaw rate, rad/s (0 when the source has none)
  /// Pipeline clock when the sample was received, checked against time_s (MotionGateConfig's
  /// clock_tolerance_s); NaN: no receiver clock (a recorded file), not checked.
  double received_s = std::numeric_limits<double>::quiet_NaN();
};

/// FiedlerSegmenter. Keeps the thumbnails of the open place's frames (at most `max_thumbnails`, oldest
/// dropped) so the closed place's representative has its picture. Dropped places (too few keypoints) are
/// counted and not passed on.
///
/// The window's clock is the frames' source time through a FrameTimeline: a source time that goes back
/// (a recording's clock stepped back, broken video PTS) is carried on from the previous frame at the
/// typical interval and counted (sourceTimeStepsBack()), logged now and then; a jump forward is a gap
/// (docs/reliability.md, "Clock jumps").
///
/// Motion (docs/segmentation.md, "Motion-aware segmentation"): samples given to addMotion() (any thread)
/// are applied to a MotionGate, in order, before the next frame; each frame then asks the gate at its
/// captured_at_s. Without samples the segmentation is exactly the one without motion.
///
/// Traversals (the offline commands' sources, OfflineRunner): beginTraversal() starts a fresh window and
/// clock; places go on being numbered over the whole run, and the sequence evidence carries on. The
/// daemon has one traversal.
class FiedlerSegmentationStage final : public SegmentationStage {
 public:
  /// `evidence` with weight > 0: every closed place carries the sequence evidence of its frames
  /// (ClosedPlace::evidence; docs/topology.md). The default has weight 0: none. With
  /// evidence.frame_revisits (or weight > 0) every frame gets the detector's answer (SegmentationStep::revisit).
  FiedlerSegmentationStage(const FiedlerSegmenterConfig& config, const SimilarityMeasure& similarity,
                           std::size_t max_thumbnails = 600, const MotionGateConfig& motion = {},
                           const SequenceEvidenceConfig& evidence = {});
  SegmentationStep process(std::int64_t sequence, double source_time_s, double captured_at_s, std::shared_ptr<const Fingerprint> fingerprint,
                           const cv::Mat& thumbnail) override;
  std::optional<ClosedPlace> finish() override;
  std::int64_t droppedPlaces() const { return dropped_places_; }
  std::int64_t keptPlaces() const { return kept_places_; }

  /// The next frame starts a traversal of its own (a new source): a fresh segmentation window (the open
  /// place must have been closed by finish()) and a fresh clock (sourceTimeline()); place numbers and the
  /// sequence evidence carry on. Frame numbers (process()'s `sequence`) must still increase.
  void beginTraversal();
  /// The place the last process() or finish() closed, kept or dropped, numbered over the run (kept and
  /// dropped places each from 0, in closing order); its representative is not kept here. Empty when that
  /// call closed none. For the run folder's places.csv and dropped_places.csv (OfflineRunner).
  const std::optional<SegmentedPlace>& lastClosedPlace() const { return last_closed_; }
  /// The segmenter's settings.
  const FiedlerSegmenterConfig& segmenterConfig() const { return segmenter_->config(); }

  /// Any thread. Queues a sample for the segmentation thread; at most kMaxPendingMotion wait (beyond,
  /// the oldest is dropped and counted in droppedMotionSamples()).
  void addMotion(const MotionSample& sample);
  static constexpr std::size_t kMaxPendingMotion = 4096;
  /// Segmentation thread (or after it ended): the gate's state at the last frame, frames skipped as
  /// standing, samples the gate refused (not finite, off the clock, implausible, time going back; by
  /// reason in motionRefusals()) or that overflowed the queue.
  MotionState lastMotion() const { return last_motion_; }
  std::int64_t skippedFrames() const { return skipped_before_ + segmenter_->skippedFrames(); }
  std::int64_t motionSamples() const { return gate_.samples(); }  ///< samples the gate took
  std::int64_t refusedMotionSamples() const { return gate_.rejectedSamples(); }
  const MotionRefusals& motionRefusals() const { return gate_.refusals(); }
  std::int64_t droppedMotionSamples() const;
  /// Segmentation thread (or after it ended): frames whose source time went back, which the window's
  /// clock carried on from the frame before (FrameTimeline).
  std::int64_t sourceTimeStepsBack() const { return timeline_.stepsBack(); }
  /// The current traversal's clock (its steps back, for a summary).
  const FrameTimeline& sourceTimeline() const { return timeline_; }
  /// The last frame's time on the window's clock (its source time with the steps back cut out), seconds.
  double lastFrameTimeS() const { return last_time_s_; }
  /// From now on, every frame writes whether motion is used and the standing frames so far into
  /// `counters` (may be null: nowhere), which must outlive the stage; any thread may read them.
  void reportMotionTo(MotionStatusCounters* counters) { motion_counters_ = counters; }
  /// Segmentation thread: whether the last frame used motion (MotionUse).
  MotionUse motionUse() const;

 private:
  /// The pipeline's record of a place the segmenter closed (nullopt when it was dropped); frees the
  /// thumbnails of its frames.
  std::optional<ClosedPlace> toClosedPlace(const SegmentedPlace& place);
  /// Logs the gate's refusals since `before`, a few of each reason.
  void warnOfRefusals(const MotionRefusals& before) const;

  const SimilarityMeasure& similarity_;
  /// What the segmenter and the sequence detector compare with: each pair of the newest frame computed once.
  FrameSimilarityMemo memo_;
  std::optional<FiedlerSegmenter> segmenter_;        ///< always set; a fresh one per traversal
  std::unique_ptr<PlaceSequenceEvidence> evidence_;  ///< null: no sequence detector
  bool evidence_to_filter_ = false;                  ///< closed places carry its evidence (weight > 0)
  std::size_t max_thumbnails_;
  /// (frame, thumbnail) of the open place's frames, in arrival order; capacity max_thumbnails_ reserved
  /// once, so a frame costs no node allocation.
  std::vector<std::pair<std::int64_t, cv::Mat>> thumbnails_;
  std::int64_t dropped_places_ = 0;
  std::int64_t kept_places_ = 0;
  std::int64_t kept_before_ = 0;     ///< kept places of earlier traversals (the segmenter numbers its own)
  std::int64_t dropped_before_ = 0;  ///< dropped places of earlier traversals
  std::int64_t skipped_before_ = 0;  ///< standing frames of earlier traversals
  std::optional<SegmentedPlace> last_closed_;

  MotionGate gate_;
  MotionState last_motion_;
  FrameTimeline timeline_;  ///< the window's clock: source times with their steps back cut out
  double last_time_s_ = 0.0;
  mutable std::mutex motion_mutex_;
  std::deque<MotionSample> pending_motion_;  ///< guarded by motion_mutex_
  std::deque<MotionSample> applying_;        ///< segmentation thread: swapped out of pending_motion_
  std::int64_t dropped_motion_ = 0;          ///< guarded by motion_mutex_
  MotionStatusCounters* motion_counters_ = nullptr;
};

/// TopologyParticleFilter with its step sliced into `stage.slice_items` work items, run until the time budget
/// (read from `clock`) is spent. Place index = filter observation index, so numbering continues across
/// restarts from a saved map. The map file (MapStore) carries, as application data, the representative
/// frame of each observation.
/// The nodes of a map's most probable topology as the localisation-only mode needs them: those with at least
/// one stored representative (the others cannot be recognised and are left out), and the edges between them.
/// Throws std::invalid_argument for a map without places or representatives.
/// A node's references are its places' representatives and their views (`views`, per observation; may be
/// shorter than the observations).
MapNodes mapNodesOf(const TopologyParticleFilter& filter, const PlaceViews& views = {});

class ParticleFilterTopologyStage final : public TopologyStage {
 public:
  ParticleFilterTopologyStage(const TopologyFilterConfig& config, const SimilarityMeasure& similarity,
                              const Clock& clock, const TopologyStageConfig& stage);
  ~ParticleFilterTopologyStage() override;
  /// Replaces the filter by the map saved at `path`. Throws MapStoreError (with the reason) if it is not
  /// a valid map.
  void loadMap(const std::string& path);
  /// Replaces the filter by a map already loaded (e.g. by MapStore::recover).
  void adoptMap(LoadedMap loaded);
  /// The settings recorded in every map snapshot (MapStore::checkSettings compares them on resume).
  void setMapSettings(MapSettings settings) { map_settings_ = std::move(settings); }
  /// How to name a frame of the source (FrameSource::frameName; any thread). With it, each snapshot records
  /// the last frame the map holds (kMapSourceLastFrameKey, kMapSourceLastFrameNameKey) when it has a name.
  void nameFramesWith(std::function<std::string(std::int64_t)> name_of) { name_of_ = std::move(name_of); }
  /// The last frame the map holds so far (a resumed map's, from its settings); -1: none yet. Set before start.
  void setLastMappedFrame(std::int64_t sequence, std::string name) {
    last_mapped_frame_ = sequence;
    last_mapped_name_ = std::move(name);
  }
  std::int64_t lastMappedFrame() const { return last_mapped_frame_; }

  /// Localisation only (map.mode: localize; docs/daemon.md): from now on the map never changes. Every frame
  /// given to observeFrame() is localised among the loaded map's nodes (NodeLocalizer) and the estimate
  /// answers for that frame (node -1: not a known node); a closed place gets the node of its
  /// representative and is never a new node. Call after loadMap()/adoptMap(). Throws
  /// std::invalid_argument for an invalid config or a map without places.
  void startLocalizing(const NodeLocalizerConfig& config);
  bool localizing() const { return localizer_ != nullptr; }
  bool observesFrames() const override { return localizing(); }
  void observeFrame(const Fingerprint& fingerprint) override;
  bool savesMap() const override { return !localizing(); }

  void enqueuePlace(ClosedPlace place) override;
  std::optional<FinishedPlace> advance(double budget_s) override;
  std::size_t queuedPlaces() const override { return queue_.size(); }
  bool idle() const override { return queue_.empty() && !filter_->stepInProgress(); }
  const PlaceEstimate& estimate() const override { return estimate_; }
  TopologySnapshot topology() const override { return topology_; }
  void locate(RevisitEstimate& r) const override;
  std::unique_ptr<const MapSnapshot> snapshotMap() const override;

  int observations() const { return filter_->observationCount(); }
  /// The filter itself, read-only (its full estimate, its config, MapStore::save); valid until the next
  /// loadMap() or adoptMap().
  const TopologyParticleFilter& filter() const { return *filter_; }
  /// Every observation's views (ClosedPlace::views), as the map stores them.
  const PlaceViews& views() const { return views_; }

 private:
  void refresh();  ///< recomputes estimate_ and topology_ after a finished step (or a load)
  FinishedPlace localizePlace(ClosedPlace place);  ///< localisation only: the place's node, no step

  const SimilarityMeasure& similarity_;
  const Clock& clock_;
  std::size_t slice_items_;
  int alternatives_;
  CandidateSelectionConfig candidates_;  ///< re-applied to a loaded map
  std::unique_ptr<TopologyParticleFilter> filter_;
  /// Closed places waiting for (or in) their filter step: the front one while a step is in progress.
  std::deque<ClosedPlace> queue_;
  std::vector<std::int64_t> representative_frames_;  ///< per observation (-1: from an older run)
  std::function<std::string(std::int64_t)> name_of_;
  std::int64_t last_mapped_frame_ = -1;  ///< the last frame of the last place stepped (or of the resumed map)
  std::string last_mapped_name_;         ///< its name ("" unnamed: not recorded)
  int run_first_observation_ = 0;  ///< observation of this run's first place (after a loaded map)
  std::vector<double> step_evidence_;  ///< scratch: the evidence by observation
  /// This run's stepped places, in step order (frames increase): where a matched frame lies.
  struct PlaceSpan {
    std::int64_t first_frame = 0, last_frame = 0;
    int observation = -1;
  };
  std::vector<PlaceSpan> spans_;
  std::vector<int> best_assignment_;  ///< node of each observation in the most probable topology (refresh())
  std::int64_t revision_ = 0;
  PlaceEstimate estimate_;
  TopologySnapshot topology_;
  MapSettings map_settings_;
  PlaceViews views_;                          ///< per observation: the place's views
  std::unique_ptr<NodeLocalizer> localizer_;  ///< localisation only
  int localized_places_ = 0;                  ///< localisation only: places of this run so far
};

}  // namespace toposlam
