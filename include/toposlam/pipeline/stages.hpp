// The small interfaces the pipeline owns. Each stage of the real-time pipeline is one of these, so a test
// can inject a fake (or a deliberately slow) stage and the daemon can wire in the real algorithms
// (VpackExtractor, FiedlerSegmenter, TopologyParticleFilter) through thin adapters. The records that
// travel between the stage threads are defined here too.
//
// Thread-safety: each stage object is used by exactly one pipeline thread (its own); sinks by the
// publisher thread only. None of them needs to be thread-safe.
#pragma once

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "toposlam/fingerprint/fingerprint.hpp"
#include "toposlam/pipeline/frame_source.hpp"

namespace toposlam {

/// A place the segmentation closed (thesis chapter 4): its frames and its representative.
struct ClosedPlace {
  int place = -1;                         ///< index of the place, from 0, in closing order
  std::int64_t first_frame = 0;           ///< sequence numbers
  std::int64_t last_frame = 0;
  std::int64_t representative_frame = 0;
  int keypoints = 0;                      ///< keypoints of the representative
  std::shared_ptr<const Fingerprint> representative;
  /// Other frames of the place (SegmentedPlace::samples) for the relative likelihood; may be empty.
  std::vector<std::shared_ptr<const Fingerprint>> samples;
  /// Its views (SegmentedPlace::views): kept in the map for localisation only; no decision uses them.
  std::vector<std::shared_ptr<const Fingerprint>> views;
  cv::Mat thumbnail;                      ///< small BGR image of the representative (may be empty)
  /// Sequence evidence (PlaceSequenceEvidence), one likelihood per earlier place of this run in closing
  /// order; empty when the segmentation stage has none.
  std::vector<double> evidence;
};

/// Whether the robot is back, frame by frame (docs/topology.md, "The per-frame answer"): the earlier frame
/// this frame matches by the sequence detector, and where that frame lies in the map. The segmentation
/// stage fills match_frame and score; the topology stage, match_place and match_node.
struct RevisitEstimate {
  std::int64_t match_frame = -1;  ///< the earlier frame the robot is back at; -1: not back, or not known yet
  double score = 0.0;             ///< the detector's score (integrated relative similarity), 0 without a match
  int match_place = -1;           ///< the place holding match_frame (-1: none, or its filter step is not done)
  int match_node = -1;            ///< that place's node in the most probable topology: the node the robot is in now
};

/// What segmentation says after one frame.
struct SegmentationStep {
  double lambda2 = std::numeric_limits<double>::quiet_NaN();  ///< Fiedler value; NaN until defined
  std::optional<ClosedPlace> closed;                          ///< a place closed by this frame
  RevisitEstimate revisit;                                    ///< the frame's match (match_frame, score)
};

/// The topology filter's decision for one place, once its (spread) step has finished.
struct PlaceAssignment {
  int place = -1;
  int node = -1;
  bool is_new = false;           ///< the node was created for this place
  double probability = 0.0;      ///< probability of this node for this place (over particles)
};

/// A place whose filter step finished: the closed place as the segmentation stage gave it (thumbnail,
/// frames, representative), numbered by the filter (ClosedPlace::place = PlaceAssignment::place, the
/// filter's observation, which goes on from a resumed map), and the filter's decision.
struct FinishedPlace {
  ClosedPlace place;
  PlaceAssignment assignment;
};

struct NodeProbability {
  int node = -1;
  double probability = 0.0;
};

/// The per-frame place estimate: where the robot is, as of the last finished filter step.
struct PlaceEstimate {
  int place = -1;                ///< last place whose step finished (-1 before the first)
  int node = -1;                 ///< its node in the most probable topology (-1 before the first)
  double probability = 0.0;
  bool is_new = false;
  std::vector<NodeProbability> alternatives;  ///< next most probable nodes for that place, best first
  std::int64_t map_revision = 0;              ///< increments with every finished step (and map load)
};

struct TopologyNode {
  int id = -1;
  std::vector<int> places;
  std::vector<std::int64_t> representative_frames;
};

struct TopologyEdge {
  int from = -1;
  int to = -1;
  int count = 0;  ///< traversals seen
};

/// The most probable topology (the best particle's map).
struct TopologySnapshot {
  std::int64_t map_revision = 0;
  double probability = 0.0;  ///< weight of the best topology among the particles
  int particles = 0;
  std::vector<TopologyNode> nodes;
  std::vector<TopologyEdge> edges;
};

// ---------------------------------------------------------------------------------------------------

/// What the fingerprint stage makes of one frame: everything later stages need of its pixels, so the
/// frame's buffer can go back to the source.
struct FingerprintedFrame {
  Fingerprint fingerprint;
  /// Small copy of the frame (BGR, or grey as the frame) for the place event of the place it may end up
  /// representing; empty when the stage makes none.
  cv::Mat thumbnail;
};

/// Frame -> fingerprint and thumbnail. Must not keep a reference to the frame's pixels after returning:
/// the frame's buffer goes back to the source right after (the thumbnail is a copy).
class FingerprintStage {
 public:
  virtual ~FingerprintStage() = default;
  /// image: the frame (BGR, or grey); grey: the camera's own grey of it, or empty (Frame::grey).
  virtual FingerprintedFrame process(const cv::Mat& image, const cv::Mat& grey) = 0;
};

/// Fingerprint -> Fiedler value and, now and then, a closed place. Called for every frame, in order.
class SegmentationStage {
 public:
  virtual ~SegmentationStage() = default;
  /// `thumbnail` is the frame's small image (for the place event of the place it may end up
  /// representing); the stage may keep it (cv::Mat shares, no copy). `captured_at_s` is the pipeline
  /// clock when the frame left the source (FrameResult::captured_at_s; the daemon's is CLOCK_MONOTONIC).
  /// source_time_s: the frame's time from its source (capture time, the simulator's clock, image
  /// timestamps), the segmentation window's clock; captured_at_s: the pipeline clock, motion's.
  virtual SegmentationStep process(std::int64_t sequence, double source_time_s, double captured_at_s,
                                   std::shared_ptr<const Fingerprint> fingerprint, const cv::Mat& thumbnail) = 0;
  /// Called once when the stream has ended (not on a stop request, after which a resumed run goes on
  /// in the same place): closes the open place, if it is kept.
  virtual std::optional<ClosedPlace> finish() = 0;
};

/// A copy of the map taken at one moment (in memory, cheap: the topology stage's freezes the filter's
/// shared state), encoded and written to disk later by another thread so that neither the encoding, which
/// grows with the map, nor the fsync stalls the frame path.
class MapSnapshot {
 public:
  virtual ~MapSnapshot() = default;
  /// Replaces the map file at `path` atomically (readers and a crash see the old or the new map, never
  /// half of one). Throws std::runtime_error (or a subclass) on I/O failure. Any thread.
  virtual void writeTo(const std::string& path) const = 0;
  /// Size of the file image in bytes (for the log; a snapshot that encodes in writeTo() knows it after).
  virtual std::size_t bytes() const = 0;
};

/// The topology filter, with its per-place step split into bounded slices of work. The stage's queue of
/// places is the one place a closed place waits for its step: it keeps the whole ClosedPlace and hands it
/// back with the filter's decision (the Pipeline bounds it, Pipeline::kPlaceQueueCapacity).
class TopologyStage {
 public:
  virtual ~TopologyStage() = default;
  /// Queues the filter step for a newly closed place (places arrive in order); the stage keeps the place.
  virtual void enqueuePlace(ClosedPlace place) = 0;
  /// Works on the queued steps for about `budget_s` seconds (it may overrun by one slice of work).
  /// Returns the place and its assignment when its step finished during this call (at most one per call).
  virtual std::optional<FinishedPlace> advance(double budget_s) = 0;
  /// Places queued, the one in its step included.
  virtual std::size_t queuedPlaces() const = 0;
  /// True when no step is queued or in progress.
  virtual bool idle() const = 0;
  /// The estimate as of the last finished step (valid until the next advance() or map load; read on
  /// the frame path, so not a copy).
  virtual const PlaceEstimate& estimate() const = 0;
  /// The most probable topology as of the last finished step.
  virtual TopologySnapshot topology() const = 0;
  /// True when the stage answers for every frame itself (localisation only): the pipeline then hands it
  /// each frame's fingerprint with observeFrame() before reading estimate().
  virtual bool observesFrames() const { return false; }
  /// One frame of the stream, in order (only when observesFrames()).
  virtual void observeFrame(const Fingerprint& /*fingerprint*/) {}
  /// False when the map must never be written (localisation only).
  virtual bool savesMap() const { return true; }
  /// Fills r.match_place and r.match_node for r.match_frame (both -1 when no finished place holds it).
  virtual void locate(RevisitEstimate& r) const {
    r.match_place = -1;
    r.match_node = -1;
  }
  /// The map as it is now, to be written by MapSnapshot::writeTo() from any thread. Only called when
  /// idle(). Throws std::runtime_error (or a subclass) if the map cannot be encoded.
  virtual std::unique_ptr<const MapSnapshot> snapshotMap() const = 0;
};

// ---------------------------------------------------------------------------------------------------

/// Latency statistics over a window of frames, in milliseconds.
struct LatencyStats {
  double median_ms = 0.0;
  double p99_ms = 0.0;
  double max_ms = 0.0;
  std::int64_t samples = 0;
};

struct StageStatus {
  std::string name;
  LatencyStats latency;         ///< this stage's own processing time per frame, last status period
  std::int64_t processed = 0;   ///< frames this stage finished since start
  std::int64_t dropped = 0;     ///< frames dropped from this stage's INPUT queue since start
  std::int64_t kept_waits = 0;  ///< producer waits on the INPUT queue: full of place records (never dropped)
  std::size_t queue_depth = 0;  ///< items waiting in its input queue now
  std::size_t queue_capacity = 0;
  double cpu_percent = 0.0;     ///< CPU time of the stage's thread over the last period (100 = one core)
};

/// Whether segmentation uses the robot's motion (docs/segmentation.md, "Motion-aware segmentation").
enum class MotionUse : int {
  None = 0,  ///< no motion sample has arrived: segmenting by time
  Used = 1,  ///< samples are fresh: standing frames are skipped (and the window is in metres, if set)
  Lost = 2,  ///< samples arrived, but none within the gate's timeout: segmenting by time again
  /// none within the timeout either, and the samples since the newest accepted one were refused (off the
  /// receiver's clock, implausible, ...): they arrive but cannot be used; segmenting by time
  Stale = 3,
};
/// "none", "used", "lost", "stale".
inline const char* toString(MotionUse use) {
  return use == MotionUse::Used ? "used" : use == MotionUse::Lost ? "lost" : use == MotionUse::Stale ? "stale" : "none";
}

/// The motion part of a status line, from the status message's motion_state, standing frames, refused samples,
/// malformed messages and abandoned fragmented messages: "motion used, 12 standing frames skipped", "motion
/// stale (segmenting by time), 0 standing frames skipped, motion refused 3, motion malformed 2, motion
/// fragments abandoned 1"; "" while no motion arrived and nothing was refused or dropped. A count of -1 (not
/// counted) is left out.
inline std::string motionStatusText(const std::string& state, std::int64_t standing_frames, std::int64_t refused,
                                    std::int64_t malformed, std::int64_t fragments_abandoned) {
  if (state == toString(MotionUse::None) && refused == 0 && malformed == 0 && fragments_abandoned <= 0) return "";
  std::string text = "motion " + state;
  if (state == toString(MotionUse::Lost) || state == toString(MotionUse::Stale)) text += " (segmenting by time)";
  text += ", " + std::to_string(standing_frames) + " standing frames skipped";
  if (refused > 0) text += ", motion refused " + std::to_string(refused);
  if (malformed > 0) text += ", motion malformed " + std::to_string(malformed);
  if (fragments_abandoned > 0) text += ", motion fragments abandoned " + std::to_string(fragments_abandoned);
  return text;
}

/// Robot motion as the daemon sees it, for the status message: the LCM receive thread counts messages,
/// the segmentation thread writes the rest, the publisher reads all three.
struct MotionStatusCounters {
  std::atomic<std::int64_t> messages{0};         ///< motion messages received
  std::atomic<int> use{static_cast<int>(MotionUse::None)};  ///< a MotionUse, at the last frame
  std::atomic<std::int64_t> standing_frames{0};  ///< frames left out of segmentation as standing
  std::atomic<std::int64_t> refused{0};          ///< samples the motion gate refused (MotionRefusals::total)
  std::atomic<std::int64_t> malformed{0};        ///< motion messages that could not be decoded (dropped)
  /// fragmented motion messages the receiver abandoned (a fragment lost); -1: not counted
  std::atomic<std::int64_t> fragments_abandoned{0};
};
/// motionStatusText of the counters as they are now.
inline std::string motionStatusText(const MotionStatusCounters& counters) {
  return motionStatusText(toString(static_cast<MotionUse>(counters.use.load())), counters.standing_frames.load(),
                          counters.refused.load(), counters.malformed.load(), counters.fragments_abandoned.load());
}

struct PipelineStatus {
  double time_s = 0.0;          ///< pipeline clock
  double uptime_s = 0.0;
  double fps = 0.0;             ///< frames published per second over the last period
  std::int64_t frames_captured = 0;
  std::int64_t frames_published = 0;
  std::int64_t frames_dropped = 0;   ///< all queues together (only per-frame estimates; places are kept)
  /// All queues together: a producer waited, the queue held only places (the topology stage's place
  /// queue included: full, its oldest step was finished first, Pipeline::kPlaceQueueCapacity).
  std::int64_t queue_kept_waits = 0;
  std::int64_t source_skipped = 0;   ///< bad frames the source skipped
  SkippedFrames source_skipped_by_reason;          ///< the same, by reason (sums to source_skipped)
  SourceKind source_kind = SourceKind::Camera;      ///< what the frames come from (the status names it)
  SourceLink source_link = SourceLink::Streaming;  ///< the camera: streaming or reconnecting
  std::int64_t source_reconnects = 0;              ///< camera outages survived
  int source_reconnect_attempts = 0;               ///< failed attempts in the current outage
  std::int64_t source_dropped = 0;                 ///< frames the driver lost (sequence gaps)
  LatencyStats latency;              ///< capture to publish, last period
  std::vector<StageStatus> stages;   ///< capture, fingerprint, segmentation, topology, publisher
  double cpu_percent = 0.0;          ///< whole process, last period (100 = one core)
  int places = 0;                    ///< places closed so far
  std::int64_t map_revision = 0;
  std::int64_t maps_saved = 0;
  std::int64_t map_save_failures = 0;  ///< failed map writes since the last one that succeeded (retried)
  std::string map_save_problem;        ///< the last failure, while map_save_failures > 0
  std::string state;                 ///< "running", "stopping", "finished"
};

/// One frame's passage through the pipeline, delivered to the sink after the topology stage.
struct FrameResult {
  bool has_frame = true;        ///< false for the final flush record (only events and topology)
  std::int64_t sequence = 0;
  double source_time_s = 0.0;   ///< Frame::timestamp_s from the source
  double captured_at_s = 0.0;   ///< pipeline clock when the frame left the source
  std::string name;
  double fingerprint_ms = 0.0, segmentation_ms = 0.0, filter_ms = 0.0;  ///< per-stage work
  int keypoints = 0;
  double lambda2 = std::numeric_limits<double>::quiet_NaN();
  std::optional<ClosedPlace> closed_place;  ///< closed by segmentation on this frame (its step is queued)
  /// The frame's fingerprint, carried to the topology stage only when it observes frames (localisation only).
  std::shared_ptr<const Fingerprint> fingerprint;
  PlaceEstimate estimate;
  RevisitEstimate revisit;                     ///< whether this frame is back at an earlier one, and where
  std::vector<FinishedPlace> finished_places;  ///< steps finished on this frame
  std::shared_ptr<const TopologySnapshot> topology;  ///< set when the topology changed on this frame
};

/// Where results go (LCM in the daemon; a recorder in tests and the benchmark).
class PipelineSink {
 public:
  virtual ~PipelineSink() = default;
  /// Per frame (has_frame) or final flush; publishes the place estimate, place events and topology.
  virtual void publish(const FrameResult& result) = 0;
  virtual void publishStatus(const PipelineStatus& status) = 0;
};

}  // namespace toposlam
