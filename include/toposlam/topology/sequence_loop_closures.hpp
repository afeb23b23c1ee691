// Frame-level loop closures by sequence evidence (docs/topology.md, "Frame level by sequences"): the
// default way `toposlam map` gives every frame its best-matching earlier frame and a score.
//
// A single frame's similarity cannot say *whether* the robot is back (on the corridor set a first-lap
// frame matches an earlier frame of the same corridor as well as a revisit does); a run of frames that
// keep matching a run of earlier frames in step can. So, at keyframes (one per `keyframe_interval_s`):
//   1. the keyframe's similarities s_g to every earlier keyframe g are made relative to each other,
//      z_g = (s_g - mean) / max(std, sigma_floor), so a frame that resembles everything scores nothing;
//   2. each z_g is integrated along the diagonal (keyframe f against g continues f-1 against g-1):
//      D(f, g) = (1 - decay) z_g + decay D(f-1, g-1), a leaky sum over the last 1 / (1 - decay) keyframes,
//      never across the start of a traversal (where the keyframes' clock goes back);
//   3. the detection is the g at least `min_gap_keyframes` back with the largest D, when D > 0, scored D.
// A frame between keyframes takes its latest keyframe's score and, as its match, the most similar frame
// around the keyframe's match shifted by the same number of frames (the robot retraces at about the
// speed of the first visit).
//
// Pure: plain vectors in, the similarity measure; no clock, no I/O. Deterministic.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "toposlam/fingerprint/fingerprint.hpp"
#include "toposlam/matching/similarity_measure.hpp"
#include "toposlam/topology/frame_loop_closures.hpp"

namespace toposlam {

struct SequenceLoopConfig {
  double keyframe_interval_s = 1.0;  ///< a keyframe at most this often (every frame of a 1 Hz sequence)
  double decay = 0.975;              ///< per keyframe: evidence of the last ~40 keyframes
  int min_gap_keyframes = 20;        ///< detections at least this many keyframes back
  double sigma_floor = 0.01;         ///< keeps z finite when the earlier similarities are all alike

  /// Empty when valid, else what is wrong (names the setting).
  std::string validate() const;
};

/// The keyframe part: one add() per keyframe, in time order. Keeps one integrated value per earlier
/// keyframe (8 bytes each); add() is linear in the keyframes so far.
class SequenceLoopDetector {
 public:
  explicit SequenceLoopDetector(SequenceLoopConfig config);

  struct Detection {
    std::int64_t keyframe = -1;  ///< the detected earlier keyframe, -1: none
    double score = 0.0;          ///< integrated relative similarity D (> 0 when detected)
    double relative = 0.0;       ///< this keyframe's own z with the detected one (not integrated)
  };

  /// similarities[g]: the new keyframe against earlier keyframe g, for every g < keyframes().
  /// continues_previous = false: the new keyframe starts a traversal (no diagonal runs from the previous
  /// keyframe into it, nor from the keyframe before it into it later on).
  Detection add(const std::vector<double>& similarities, bool continues_previous = true);

  std::int64_t keyframes() const { return static_cast<std::int64_t>(integrated_.size()); }

 private:
  SequenceLoopConfig config_;
  std::vector<double> integrated_;  ///< D(latest keyframe, g) for g < latest
  std::vector<double> next_;        ///< scratch, reused
  std::vector<bool> starts_run_;    ///< per keyframe: the first of its traversal
};

/// Sequence evidence for the topology filter (docs/topology.md, "Sequence evidence in the filter"): the
/// same detector run online over a stream's frames, read per place. When a kept place closes, each earlier
/// kept place gets the share of the new place's keyframes whose detection (score >= min_score) lies in
/// it, times `weight`: a likelihood in [0, weight] that TopologyParticleFilter::beginStep takes beside
/// the representatives' own (the larger of the two counts). A revisit that single frames cannot tell from
/// a look-alike (a corridor) is then closed on the run of frames that keeps matching in step.
struct SequenceEvidenceConfig {
  SequenceLoopConfig loop;
  double min_score = 0.1;  ///< the detection's D needed to count (the corridor's first lap stays below 0.05)
  /// Likelihood of an earlier place every keyframe of the new place detects into; 0 = off (the default:
  /// it closes look-alike stretches of one lap, docs/topology.md). 0.99 when turned on.
  double weight = 0.0;
  /// The keyframe's own relative similarity z with the detected keyframe needed to count: a run's evidence
  /// fades slowly after the revisit ends, and without this the diagonal it leaves behind keeps voting.
  double min_relative = 0.0;
  /// The share of the new place's keyframes an earlier place needs before it gets any evidence: weak
  /// evidence would otherwise decide (eq. 5.7's new-node likelihood falls with the entropy of the known
  /// nodes' likelihoods, so one small but lone likelihood beats a new node).
  double min_share = 0.8;

  /// Empty when valid, else what is wrong (names the setting).
  std::string validate() const;
};

/// Online, one instance per stream (the daemon's segmentation stage, `toposlam map`). Keeps the keyframes'
/// fingerprints (one per keyframe_interval_s) and the frame ranges of the kept places; addFrame() costs one
/// similarity per earlier keyframe at a keyframe, nothing otherwise. Not thread-safe.
class PlaceSequenceEvidence {
 public:
  PlaceSequenceEvidence(const SequenceEvidenceConfig& config, const SimilarityMeasure& similarity);

  /// Every frame in stream order (frame numbers increasing). A null fingerprint is skipped. A time that
  /// goes back, or the first frame after beginTraversal(), starts a new traversal.
  void addFrame(std::int64_t frame, double time_s, const std::shared_ptr<const Fingerprint>& fingerprint);
  /// The next frame starts a traversal of its own (a new source).
  void beginTraversal() { traversal_break_ = true; }
  /// A kept place [first_frame, last_frame] closed (its frames were all added): returns one likelihood per
  /// earlier kept place, in the order they closed, and records this place. Places must not overlap.
  std::vector<double> closePlace(std::int64_t first_frame, std::int64_t last_frame);

  std::int64_t keyframes() const { return detector_.keyframes(); }

 private:
  /// Index of the kept place holding `frame`, -1 if none.
  std::int64_t placeOfFrame(std::int64_t frame) const;

  SequenceEvidenceConfig config_;
  const SimilarityMeasure& similarity_;
  SequenceLoopDetector detector_;
  std::vector<std::shared_ptr<const Fingerprint>> keyframe_fingerprints_;
  std::vector<std::int64_t> keyframe_frames_;
  double last_keyframe_time_s_ = 0.0;
  bool traversal_break_ = true;
  struct KeyframeDetection {
    std::int64_t frame = -1;          ///< the keyframe
    std::int64_t matched_frame = -1;  ///< its detection (-1: none that counts)
  };
  std::vector<KeyframeDetection> open_detections_;  ///< keyframes not yet in a closed place
  std::vector<std::pair<std::int64_t, std::int64_t>> places_;  ///< kept places' frame ranges, in order
  std::vector<double> row_;                                     ///< scratch
};

/// Whole runs: time_s[f] per frame (a time that goes back starts a new traversal: that frame is a
/// keyframe), fingerprints[f] may be null (never a keyframe or a candidate). Returns one FrameMatch per
/// frame (similarity: with the match; score: the keyframe's D).
std::vector<FrameMatch> matchFramesBySequence(const std::vector<double>& time_s,
                                              const std::vector<std::shared_ptr<const Fingerprint>>& fingerprints,
                                              const SimilarityMeasure& similarity, const SequenceLoopConfig& config);

}  // namespace toposlam
