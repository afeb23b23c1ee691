// Frame-level loop closures by sequence evidence (docs/topology.md, "Frame level by sequences"): run online
// in the segmentation stage, the one data path of toposlamd and `toposlam map`, it gives every frame, as it
// arrives, its best-matching earlier frame and a score (place_t's match_*, frames.csv's match columns).
//
// A single frame's similarity cannot say *whether* the robot is back (on the corridor set a first-lap
// frame matches an earlier frame of the same corridor as well as a revisit does); a run of frames that
// keep matching a run of earlier frames in step can. So, at keyframes (one per `keyframe_interval_s`):
//   1. the keyframe's similarities s_g to every earlier keyframe g are made relative to each other,
//      z_g = (s_g - mean) / max(std, sigma_floor), so a frame that resembles everything scores nothing;
//   2. each z_g is integrated along the diagonal (keyframe f against g continues f-1 against g-1) at
//      `scales` memories, the longest `decay` per keyframe and each next one `scale_ratio` times shorter:
//      D_k(f, g) = (1 - d_k) z_g + d_k D_k(f-1, g-1), never across the start of a traversal (where the
//      keyframes' clock goes back);
//   3. each D_k is measured in its own noise: were the z independent with unit spread, D_k would spread by
//      sigma_k = sqrt((1 - d_k) / (1 + d_k)); the score of g is max_k D_k(f, g) / sigma_k, so a short run
//      of strong matches and a long run of weak ones are judged on one scale, and the stream's own
//      similarity statistics (step 1) set it: nothing to retune per data set;
//   4. the detection is the g at least `min_gap_keyframes` back with the largest score, when its D > 0;
//      its match is the keyframe within `align_keyframes` of g that the new keyframe resembles most.
// A frame between keyframes takes its latest keyframe's score and, as its match, the keyframe's match
// shifted by the same number of frames (the robot retraces at about the speed of its first visit).
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
#include "toposlam/topology/place_candidate_index.hpp"

namespace toposlam {

struct SequenceLoopConfig {
  double keyframe_interval_s = 1.0;  ///< a keyframe at most this often (every frame of a 1 Hz sequence)
  double decay = 0.975;              ///< per keyframe, of the longest memory: evidence of the last ~40 keyframes
  int scales = 1;                    ///< memories integrated side by side, 1 .. 8
  double scale_ratio = 4.0;          ///< each next memory this many times shorter: 1 - d_{k+1} = ratio (1 - d_k)
  int min_gap_keyframes = 20;        ///< detections at least this many keyframes back
  double sigma_floor = 0.01;         ///< keeps z finite when the earlier similarities are all alike
  /// The detection's diagonal says *that* the robot is back; the match is the keyframe within this many
  /// keyframes of the diagonal's end that the new keyframe resembles most (the two visits' speeds differ a
  /// little, and a diagonal carried past the end of the earlier visit points where the robot is not).
  int align_keyframes = 1;
  /// Diagonals ending within this many keyframes of the best one belong to its run; the best diagonal
  /// outside (Detection::runner_up) says how distinct the detection is.
  int distinct_keyframes = 5;

  /// Empty when valid, else what is wrong (names the setting).
  std::string validate() const;
  /// The decay of memory k (0: the longest), clamped to >= 0.
  double decayOf(int k) const;
};

/// The keyframe part: one add() per keyframe, in time order. Keeps one integrated value per earlier
/// keyframe (8 bytes each); add() is linear in the keyframes so far.
class SequenceLoopDetector {
 public:
  explicit SequenceLoopDetector(SequenceLoopConfig config);

  struct Detection {
    std::int64_t keyframe = -1;  ///< the detected earlier keyframe (aligned), -1: none
    double score = 0.0;          ///< the best diagonal's D_k / sigma_k (> 0 when detected)
    double relative = 0.0;       ///< this keyframe's own z with the diagonal's end (not integrated)
    std::int64_t diagonal = -1;  ///< where the best diagonal ends, before alignment
    /// The best score of a diagonal ending more than distinct_keyframes from it (0: none): a periodic
    /// building gives several runs alike, a revisit one that stands out.
    double runner_up = 0.0;
  };

  /// similarities[g]: the new keyframe against earlier keyframe g, for every g < keyframes().
  /// continues_previous = false: the new keyframe starts a traversal (no diagonal runs from the previous
  /// keyframe into it, nor from the keyframe before it into it later on).
  Detection add(const std::vector<double>& similarities, bool continues_previous = true);
  /// The same with only some similarities known (NaN: not compared; its z counts as 0, the mean) and the
  /// relative similarity's mean and spread given (measured on a sample of the earlier keyframes): the cost
  /// of a keyframe then no longer grows with the keyframes compared (PlaceSequenceEvidence, large maps).
  Detection addSparse(const std::vector<double>& similarities, double mean, double spread, bool continues_previous);
  /// The earlier keyframes whose similarity the next keyframe's live diagonals need: for each memory, the
  /// `per_memory` diagonals with the largest positive D now, each continued one keyframe on (g + 1) with
  /// its neighbours for the alignment. Sorted, no repeats.
  std::vector<std::size_t> continuations(std::size_t per_memory) const;

  std::int64_t keyframes() const { return static_cast<std::int64_t>(starts_run_.size()); }
  /// The latest keyframe was published as back at `earlier`: from now on the two count as one place, so a
  /// later visit's runs to both are one run, not a runner-up (a third visit stands out as well as the second).
  void link(std::int64_t earlier);

 private:
  SequenceLoopConfig config_;
  std::vector<std::vector<double>> integrated_;  ///< per memory: D_k(latest keyframe, g) for g < latest
  std::vector<double> next_;                     ///< scratch, reused
  std::vector<double> z_;                        ///< scratch: this keyframe's relative similarities
  std::vector<double> score_;                    ///< scratch: each earlier keyframe's best score
  Detection integrate(const std::vector<double>& similarities, bool continues_previous);
  std::vector<bool> starts_run_;    ///< per keyframe: the first of its traversal
  std::vector<std::int64_t> place_;  ///< per keyframe: the earliest keyframe of its place (itself unless linked)
};

/// Sequence evidence for the topology filter (docs/topology.md, "Sequence evidence in the filter"): the
/// same detector run online over a stream's frames, read per place. When a kept place closes, each earlier
/// kept place gets the share of the new place's keyframes whose detection (score >= min_score) lies in
/// it, times `weight`: a likelihood in [0, weight] that TopologyParticleFilter::beginStep takes beside
/// the representatives' own (the larger of the two counts). A revisit that single frames cannot tell from
/// a look-alike (a corridor) is then closed on the run of frames that keeps matching in step.
struct SequenceEvidenceConfig {
  /// The detector's settings: keyframe_interval_s, scales and the rest as given; its decay and minimum gap
  /// are made from memory_s and min_gap_s below (loopConfig()), so every setting is in seconds.
  SequenceLoopConfig loop{1.0, 0.975, 3, 4.0, 20};
  double memory_s = 40.0;   ///< the longest memory's time constant: decay = 1 - keyframe interval / memory_s
  double min_gap_s = 20.0;  ///< detections at least this long back
  /// The detection's score (in its noise's standard deviations, SequenceLoopDetector) needed to count: to
  /// be published as a frame's match and to vote for the filter's evidence.
  double min_score = 2.0;
  /// ... and stand out from every other run by this much (standard deviations): a run as good as another
  /// one elsewhere (Detection::runner_up) cannot say where the robot is. Earlier places it was published
  /// back at count as one place, so a third visit stands out as well as the second.
  double min_margin = 0.5;
  double distinct_s = 5.0;  ///< runs ending within this long of the best one are its own, not a runner-up
  /// Likelihood of an earlier place every keyframe of the new place detects into; 0 = off (the thesis).
  /// The default preset sets it (method_preset.cpp; chosen in docs/results.md).
  double weight = 0.0;
  /// The keyframe's own relative similarity z with the detected keyframe needed to count: a run's evidence
  /// fades slowly after the revisit ends, and without this the diagonal it leaves behind keeps voting.
  /// Large maps: up to this many keyframes every earlier keyframe is compared (exact); beyond, only the
  /// keyframes the candidate index finds (`candidates`), the live diagonals' continuations (`diagonals` per
  /// memory) and a fixed `statistics_sample` for the mean and spread: a bounded cost per keyframe.
  /// Fingerprints without binary descriptors (SIFT) are always compared exhaustively.
  int exhaustive_up_to = 1000;
  int candidates = 32;
  int diagonals = 32;
  int statistics_sample = 128;
  /// -1e6 (the default): no such test; measured, it cost the real samples a right frame and the corridor two
  /// (docs/topology.md, "The per-frame answer").
  double min_relative = -1e6;
  /// The share of the new place's keyframes an earlier place needs before it gets any evidence: weak
  /// evidence would otherwise decide (eq. 5.7's new-node likelihood falls with the entropy of the known
  /// nodes' likelihoods, so one small but lone likelihood beats a new node).
  double min_share = 0.8;
  /// Run the detector for the per-frame answer (FrameRevisit: the earlier frame each frame is back at,
  /// published in place_t) even when the filter takes no evidence (weight 0). Off in the thesis preset.
  bool frame_revisits = true;

  /// Empty when valid, else what is wrong (names the setting).
  std::string validate() const;
  /// `loop` with its decay and minimum gap from memory_s and min_gap_s.
  SequenceLoopConfig loopConfig() const;
};

/// The per-frame answer of the sequence detector: the earlier frame this frame is back at, when the run of
/// keyframes ending at the frame's keyframe says so (its detection's D >= min_score and its own relative
/// similarity z >= min_relative: the same test that makes a keyframe vote for the filter's evidence, so the
/// frame-level answer and the evidence agree). A frame between keyframes takes its keyframe's match shifted
/// by as many frames as it lies after its keyframe (the robot retraces at about the speed of its first visit).
struct FrameRevisit {
  std::int64_t match_frame = -1;  ///< the earlier frame, -1: not back (or not known yet)
  double score = 0.0;             ///< the keyframe's integrated relative similarity D (0 without a match)
};

/// Online, one instance per stream (the daemon's segmentation stage, `toposlam map`). Keeps the keyframes'
/// fingerprints (one per keyframe_interval_s) and the frame ranges of the kept places; addFrame() costs one
/// similarity per earlier keyframe at a keyframe, nothing otherwise. Not thread-safe.
class PlaceSequenceEvidence {
 public:
  PlaceSequenceEvidence(const SequenceEvidenceConfig& config, const SimilarityMeasure& similarity);

  /// Every frame in stream order (frame numbers increasing). A null fingerprint is skipped. A time that
  /// goes back, or the first frame after beginTraversal(), starts a new traversal.
  /// Returns the frame's answer (no match for a skipped frame).
  FrameRevisit addFrame(std::int64_t frame, double time_s, const std::shared_ptr<const Fingerprint>& fingerprint);
  /// The next frame starts a traversal of its own (a new source).
  void beginTraversal() { traversal_break_ = true; }
  /// A kept place [first_frame, last_frame] closed (its frames were all added): returns one likelihood per
  /// earlier kept place, in the order they closed, and records this place. Places must not overlap.
  std::vector<double> closePlace(std::int64_t first_frame, std::int64_t last_frame);

  std::int64_t keyframes() const { return detector_.keyframes(); }
  /// Similarities computed so far (the cost: exhaustive, one per earlier keyframe per keyframe; bounded
  /// beyond exhaustive_up_to).
  std::int64_t comparisons() const { return compared_; }

 private:
  /// row_ := the new keyframe's similarities (NaN where not compared); mean and spread for addSparse.
  void compareSparse(const Fingerprint& fingerprint, double& mean, double& spread);
  /// Index of the kept place holding `frame`, -1 if none.
  std::int64_t placeOfFrame(std::int64_t frame) const;

  SequenceEvidenceConfig config_;
  const SimilarityMeasure& similarity_;
  SequenceLoopDetector detector_;
  std::unique_ptr<PlaceCandidateIndex> index_;  ///< the keyframes' descriptors (large maps)
  std::int64_t compared_ = 0;                   ///< similarities computed so far
  std::vector<std::shared_ptr<const Fingerprint>> keyframe_fingerprints_;
  std::vector<std::int64_t> keyframe_frames_;
  double last_keyframe_time_s_ = 0.0;
  bool traversal_break_ = true;
  FrameRevisit last_keyframe_revisit_;  ///< the latest keyframe's answer
  struct KeyframeDetection {
    std::int64_t frame = -1;          ///< the keyframe
    std::int64_t matched_frame = -1;  ///< its detection (-1: none that counts)
  };
  std::vector<KeyframeDetection> open_detections_;  ///< keyframes not yet in a closed place
  std::vector<std::pair<std::int64_t, std::int64_t>> places_;  ///< kept places' frame ranges, in order
  std::vector<double> row_;                                     ///< scratch
};

}  // namespace toposlam
