// Online place segmentation by algebraic connectivity (thesis chapter 4).
//
// Each new frame joins a sliding window of the last n frames (the thesis' 25) or seconds. Only its
// similarities with the other n-1 frames are computed (2 (n-1) calls to SimilarityMeasure::similarity, the mean of both
// directions); the rest of the symmetric affinity matrix A (zero diagonal) is cached. The window is a
// ring: a frame keeps its slot (row/column of A) until it leaves, and since eigenvalues do not depend on
// the order of the nodes, A is never shifted. From A: degrees d_i = sum_j a_ij, the normalised
// symmetric Laplacian L_sym = I - D^-1/2 A D^-1/2, and its second-smallest eigenvalue lambda2 (the
// Fiedler value, Eigen's SelfAdjointEigenSolver). lambda2 feeds the valley detector (Algorithm 4.1);
// a confirmed valley closes the open place.
//
// Degenerate windows: a frame with degree 0 (similarity 0 with every other frame) is an isolated node.
// For it D^-1/2 is defined as 0 and, following Chung, its diagonal entry of L_sym as 0 too, so an
// isolated node is a connected component of its own (eigenvalue 0) and lambda2 of a disconnected
// window is 0. All-zero similarities therefore give lambda2 = 0. A window of one frame has no lambda2.
//
// Where a place ends (CutPlacement): the valley of lambda2 is the moment the window is split most
// evenly between two places, i.e. about n/2 frames after the robot changed place. WindowSplit (the
// default) therefore cuts the window of the valley frame at its best temporal split: the border that
// minimises the normalised cut cut(S, T) (1/vol S + 1/vol T) of S = older frames and T = newer ones
// (the sparsest cut the Fiedler vector approximates, restricted to splits in time). ValleyFrame is the
// literal reading of Algorithm 4.1: the place ends at the valley frame itself.
//
// Representative (section 4.2.3): after every frame, the preferred window frame (of the open place) is
// remembered with its degree; when a place closes, its representative is the preferred remembered
// candidate inside the place. Preferred means: a frame with at least `min_keypoints` keypoints beats
// one with fewer (a featureless doorway view matches everything by colour and so often has the largest
// degree, but it would get the place dropped); then the larger degree; then the earlier frame. So that a
// short place always has a candidate, the moment the detector records a new lambda2 minimum (the
// future border) also remembers the best window frame before that border. A place whose
// representative has fewer than `min_keypoints` keypoints (no member had enough) is reported as
// dropped. Candidates older than
// any possible future border all fall in the open place, so only their best is kept: memory stays
// O(window) except while a valley candidate waits for confirmation. RepresentativeChoice::PlaceMedoid
// instead samples the place's frames (at most kMaxPlaceSamples) and takes the sample most similar to the
// others, each weighted by the frames it stands for (docs/segmentation.md: measured, not the default).
//
// Deterministic; independent of time (timestamps are passed through). Not thread-safe: one instance
// per stream. After the window is full, addFrame() does not allocate, closing places included
// (test_segmentation_alloc counts malloc calls); the similarity measure's own allocations aside.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "toposlam/fingerprint/fingerprint.hpp"
#include "toposlam/matching/similarity_measure.hpp"
#include "toposlam/segmentation/doorway_passage.hpp"
#include "toposlam/segmentation/motion_gate.hpp"
#include "toposlam/segmentation/valley_detector.hpp"

namespace toposlam {

enum class CutPlacement : std::uint8_t {
  WindowSplit = 0,  ///< border at the best temporal normalised cut of the valley frame's window
  ValleyFrame = 1,  ///< the place ends at the valley frame (Algorithm 4.1 read literally)
};
const char* toString(CutPlacement placement);
/// Parses "window-split" or "valley-frame"; throws std::invalid_argument otherwise.
CutPlacement parseCutPlacement(const std::string& name);

/// How a closed place's representative is chosen (docs/segmentation.md, "Representatives").
enum class RepresentativeChoice : std::uint8_t {
  WindowDegree = 0,  ///< the thesis (section 4.2.3): the remembered window frame with the largest degree
  PlaceMedoid = 1,   ///< the sampled frame of the place most similar to the place's other samples
};
const char* toString(RepresentativeChoice choice);
/// Parses "window-degree" or "place-medoid"; throws std::invalid_argument otherwise.
RepresentativeChoice parseRepresentativeChoice(const std::string& name);

struct FiedlerSegmenterConfig {
  /// The sliding window in time, seconds (docs/segmentation.md, "A window in time"): the window holds
  /// the frames taken less than window_s before the newest one, from the frames' own timestamps, so
  /// the places found do not depend on the frame rate. Allowed [0, 3600]; 0 = count frames instead
  /// (exactly `window` frames). Thesis: 25 frames at ~5 fps, i.e. 5 s.
  double window_s = 0.0;
  /// With window_s = 0: frames in the window, allowed [3, 1000]; thesis 25 (its preset). With window_s > 0:
  /// the most frames the window may hold. The default is the key table's (segmentation.window; a test holds
  /// them equal).
  int window = 100;
  /// With window_s > 0 or window_m > 0: the fewest frames the window keeps however long (or far) they
  /// took; allowed [3, window].
  int min_window_frames = 5;
  /// Motion-aware segmentation (docs/segmentation.md, "Motion-aware segmentation"): for frames added with
  /// a known MotionState, the window holds the frames taken less than window_m metres of travel before
  /// the newest one (within min_window_frames .. window), at any speed. Frames without known motion (no
  /// motion input, or the link lost) fall back to window_s / window. Allowed [0, 1000]; 0 = off (thesis
  /// suggests about 1.5 - 1.75 m).
  double window_m = 0.0;
  /// With motion known and window_m > 0: a frame taken less than min_frame_spacing_m of travel AND less
  /// than min_frame_spacing_rad of turning after the last frame added is not added (thinnedFrames()), so
  /// the window holds the same density of views at any speed; a slow stretch no longer packs it with
  /// near-identical frames (docs/segmentation.md, "Motion-aware segmentation"). Allowed [0, 100] m and
  /// [0, 10] rad; 0 m = off. Default preset 0.09 m and 0.03 rad (measured on the simulated office).
  double min_frame_spacing_m = 0.0;
  double min_frame_spacing_rad = 0.0;
  /// Subtracted from every similarity before it enters the affinity matrix (clamped at 0), so frames
  /// of different places, which still match ~0.15 by colour, become unlinked. Allowed [0, 1).
  double similarity_floor = 0.0;
  /// Peak/valley thresholds on lambda2. Thesis: gamma 0.5, delta 0.25; ours gamma 0.5, delta 0.30 (see
  /// docs/segmentation.md for how they relate to our similarity scale).
  ValleyDetectorConfig valley{0.5, 0.30};
  int min_keypoints = 15;  ///< places whose representative has fewer keypoints are dropped (thesis: 15)
  CutPlacement cut_placement = CutPlacement::WindowSplit;
  /// Borders at doorways (docs/segmentation.md, "Borders at doorways"), from the doorway passages that
  /// DoorwayPassageDetector predicts from the frames' vertical edges. When > 0, a border found by
  /// appearance moves to the passage nearest to it when one is at most this many seconds away. Allowed
  /// [0, 60]; 0 = off (the thesis).
  double doorway_shift_s = 0.0;
  /// With doorway_shift_s > 0 and segmentation by time (window_m 0), passages also make borders: a
  /// passage the frames reach closes the open place there (unless a border is on it already), a valley
  /// still pending when it does (lambda2 fell, has not risen yet, both sides a window long) closes the
  /// place at its own border first, and a border whose nearest passage is the one the open place began
  /// at is dropped (one border per doorway).
  /// With window_m > 0 the passages only move borders: they are timed on the clock, assuming the robot
  /// keeps its speed, which segmenting by travel is there not to assume (docs/segmentation.md). Off here
  /// (the thesis); on in the default preset.
  bool doorway_borders = false;
  /// The representative rule; both prefer frames with at least min_keypoints keypoints.
  RepresentativeChoice representative = RepresentativeChoice::WindowDegree;
  /// PlaceMedoid: the place's frames are sampled at most this often (its first frame always; allowed
  /// [0, 3600] s, 0 = every frame); at most kMaxPlaceSamples are kept, halving the rate when full.
  /// The same interval spaces the place samples below.
  double representative_interval_s = 0.5;
  static constexpr int kMaxPlaceSamples = 64;
  /// Besides its representative, a closed place carries up to this many of its frames (with at least
  /// min_keypoints keypoints, one per representative_interval_s at most, spread evenly over the place),
  /// which the relative likelihood compares with the stored representatives too (docs/topology.md,
  /// "Place samples"). Allowed [0, kMaxQuerySamples]; 0 = the representative alone (the thesis).
  int place_samples = 0;
  static constexpr int kMaxQuerySamples = 16;
  /// Besides its representative, a closed place keeps up to this many of its frames as views (picked as
  /// the samples above, spread evenly over the place): the map stores them, and the localisation-only
  /// mode recognises the place by them from any part of it (docs/daemon.md, "Localisation only"). They
  /// change no mapping decision. Allowed [0, kMaxQuerySamples]; 0 = the representative alone.
  int place_views = 0;
  /// Returns "" when valid, else "<key>: <problem, allowed range>".
  std::string validate() const;
};

/// The largest Fiedler value of L_sym for n nodes (a complete graph): n / (n - 1) (thesis eq. 4.6).
double maxFiedlerValue(int nodes);

/// Fiedler value of a symmetric, non-negative affinity matrix (diagonal ignored), with the degree-0
/// convention above. Throws std::invalid_argument for a non-square matrix; 0 for fewer than 2 nodes.
double fiedlerValue(const Eigen::MatrixXd& affinity);

/// Why a place ended (places.csv's `end` column; docs/segmentation.md lists the rules).
enum class PlaceEnd : std::uint8_t {
  Valley,             ///< a confirmed lambda2 valley, its border where appearance puts it
  ValleyAtDoorway,    ///< a confirmed valley whose border moved to a doorway passage (rule 2)
  DoorwayPassage,     ///< the frames reached a doorway passage (rule 1)
  InterruptedValley,  ///< a pending valley closed at its border when a passage came (rule 4)
  StreamEnd,          ///< the last frame (flush)
};
/// "valley", "valley_at_doorway", "doorway", "interrupted_valley", "stream_end".
const char* placeEndName(PlaceEnd end);

/// A closed place: frames [first_frame, last_frame] of the stream.
struct SegmentedPlace {
  std::int64_t first_frame = 0;
  std::int64_t last_frame = 0;
  double first_time_s = 0.0;
  double last_time_s = 0.0;
  std::int64_t representative_frame = 0;
  /// WindowDegree: its degree in the window it was remembered from; PlaceMedoid: the sum of its
  /// similarities with the place's other samples.
  double representative_degree = 0.0;
  std::shared_ptr<const Fingerprint> representative;
  int representative_keypoints = 0;
  /// The first sample_count are up to place_samples other frames of the place, in frame order (see
  /// FiedlerSegmenterConfig); a fixed array, so closing a place allocates nothing.
  std::array<std::shared_ptr<const Fingerprint>, FiedlerSegmenterConfig::kMaxQuerySamples> samples{};
  int sample_count = 0;
  /// Up to place_views frames of the place (not the representative), in frame order, for the map.
  std::vector<std::shared_ptr<const Fingerprint>> views;
  bool dropped = false;            ///< representative had fewer than min_keypoints keypoints
  /// Frame of the lambda2 valley that closed it, or (doorway_borders) the border frame of the doorway
  /// passage that did; -1 when flushed (the end of the stream).
  std::int64_t valley_frame = -1;
  /// Sequence number among kept places (dropped == false) or among dropped places, from 0.
  std::int64_t index = 0;
  PlaceEnd end = PlaceEnd::Valley;
};

/// What one addFrame() produced.
struct SegmenterStep {
  std::int64_t frame = 0;
  std::optional<double> lambda2;               ///< empty while the window holds one frame
  std::optional<SegmentedPlace> closed_place;  ///< a place closed by a valley confirmed at this frame
  bool skipped = false;  ///< motion said the robot stands: the frame was not added (no lambda2)
};

class FiedlerSegmenter {
 public:
  /// `similarity` must outlive the segmenter. Throws std::invalid_argument on an invalid config.
  FiedlerSegmenter(const FiedlerSegmenterConfig& config, const SimilarityMeasure& similarity);

  /// Adds the next frame. frame_index must increase strictly (gaps are allowed); throws
  /// std::invalid_argument otherwise or when `fingerprint` is null.
  SegmenterStep addFrame(std::int64_t frame_index, double time_s,
                         std::shared_ptr<const Fingerprint> fingerprint);
  /// Motion-aware: with motion.known and motion.standing, the frame is not added (step.skipped; nothing
  /// changes but the skipped count); with motion.known and window_m > 0 the window is sized by
  /// motion.distance_m. With !motion.known, exactly addFrame(frame_index, time_s, fingerprint).
  SegmenterStep addFrame(std::int64_t frame_index, double time_s, std::shared_ptr<const Fingerprint> fingerprint,
                         const MotionState& motion);

  /// End of stream: closes the open place (if it has frames) and returns it. Frames added afterwards
  /// start a new place; the window and the detector keep their state.
  std::optional<SegmentedPlace> flush();

  const FiedlerSegmenterConfig& config() const { return config_; }
  /// Frames currently in the window (<= config().window).
  int windowFrames() const { return count_; }
  /// True once the window spans its full length (window_m, window_s, or `window` frames): lambda2 goes to the
  /// valley detector only from then on.
  bool windowFull() const { return window_full_; }
  /// First frame of the open place, or -1 before any frame.
  std::int64_t openPlaceStart() const { return place_start_; }
  /// Valleys that could not close a place (their best split fell before the open place started).
  std::int64_t ignoredValleys() const { return ignored_valleys_; }
  /// Frames left out because motion said the robot stood.
  std::int64_t skippedFrames() const { return skipped_frames_; }
  /// Frames left out as too close (min_frame_spacing_m / _rad) to the last frame added.
  std::int64_t thinnedFrames() const { return thinned_frames_; }
  /// doorway_shift_s: borders moved to a doorway passage; doorway_borders: borders dropped because the
  /// place began at their passage, and places closed by a passage alone; doorway passages seen.
  std::int64_t doorwayShifts() const { return doorway_shifts_; }
  std::int64_t doorwayRepeats() const { return doorway_repeats_; }
  std::int64_t doorwayBorders() const { return doorway_borders_; }
  /// doorway_borders: places closed at a pending valley's border because a passage came before the
  /// valley's rise (rule 4).
  std::int64_t interruptedValleys() const { return interrupted_valleys_; }
  std::int64_t doorwayPassages() const { return doorway_.passageCount(); }
  /// Current cached affinity matrix, rows/columns in window order (oldest first); for tests and plots.
  Eigen::MatrixXd affinityInWindowOrder() const;

 private:
  /// doorway_borders in effect: rules 1 and 3 of docs/segmentation.md, by time only (see the config).
  bool passagesMakeBorders() const {
    return config_.doorway_shift_s > 0.0 && config_.doorway_borders && !(config_.window_m > 0.0);
  }
  struct Candidate {
    std::int64_t frame;
    double degree;
    double time_s;
    std::shared_ptr<const Fingerprint> fingerprint;
    int keypoints;
    double weight = 1.0;  ///< PlaceMedoid samples: the frames it stands for at the sampling rate
  };
  /// The representative preference of the header comment: true when `a` is the better candidate.
  bool preferred(const Candidate& a, const Candidate& b) const;

  /// Throws std::invalid_argument for a null fingerprint or a frame index that does not increase.
  void checkNextFrame(std::int64_t frame_index, const Fingerprint* fingerprint) const;
  /// addFrame with the distance travelled at the frame (NaN = motion unknown).
  SegmenterStep addFrameAt(std::int64_t frame_index, double time_s, std::shared_ptr<const Fingerprint> fingerprint,
                           double distance_m);
  int slotAtPosition(int position) const;  ///< window position 0 = oldest frame
  double computeLambda2();
  /// Remembers the window frame with the largest degree among frames in [from_frame, before_frame).
  void rememberBestWindowFrame(std::int64_t from_frame, std::int64_t before_frame);
  void addCandidate(const Candidate& candidate);
  void compactCandidates();
  /// Window position of the first frame of the newer part at the best split; -1 when none qualifies.
  int bestSplitPosition() const;
  /// PlaceMedoid: samples the frame just added to the window (slot) when the sampling interval allows.
  void samplePlaceFrame(int slot);
  /// PlaceMedoid: keeps every other sample and halves the sampling rate (the samples array is full).
  void thinPlaceSamples();
  /// PlaceMedoid: the preferred medoid among the first `count` samples (index, weighted similarity sum
  /// with the others); none when count is 0.
  std::optional<std::pair<int, double>> placeMedoid(int count) const;
  /// PlaceMedoid: forgets the first `count` samples (a closed place's).
  void dropPlaceSamples(int count);
  /// place_samples > 0: keeps the frame just added (slot) as a place sample when it has min_keypoints
  /// keypoints and the sampling interval allows.
  void sampleQueryFrame(int slot);
  /// place_samples > 0: moves up to place_samples of the samples in [place.first_frame, last_frame]
  /// (not the representative), spread evenly, into place.samples, and forgets the samples up to
  /// last_frame.
  void takeQuerySamples(SegmentedPlace& place, std::int64_t last_frame);
  /// doorway_shift_s: moves the pending border to the doorway passage nearest to it, when there is one
  /// and the border stays inside (place start, newest frame] with a representative candidate before it.
  /// False when the border is to be dropped (doorway_borders: its nearest passage is the one the open
  /// place began at).
  bool moveBorderToDoorway();
  /// doorway_borders: a passage the frames have reached closes the open place at the first recent frame
  /// at or after it, unless the place began there (a border was moved to it) or after it.
  std::optional<SegmentedPlace> closePlaceAtPassage(double passage_s);
  /// doorway_borders: a passage the frames have reached while a valley is pending (lambda2 fell by delta
  /// and has not risen yet) closes the open place at the valley's border first, when both the place
  /// before that border and the stretch from it to the passage span a window (docs/segmentation.md,
  /// rule 4). None otherwise.
  std::optional<SegmentedPlace> closePlaceAtInterruptedValley(double passage_s);
  struct RecentBorder {
    std::int64_t border = -1;  ///< first recent frame at or after the time; -1 = none
    double border_time_s = 0.0;
    std::int64_t last = -1;    ///< the recent frame before it; -1 = none
    double last_time_s = 0.0;
  };
  /// The recent frames a border at time_s falls on (the newest two for a time still ahead).
  RecentBorder recentBorderAt(double time_s) const;
  /// True when the open place has a representative candidate in [from, to] (and the representative
  /// bounds of a doorway shift).
  bool hasCandidateIn(std::int64_t from, std::int64_t to) const;
  /// Closes the open place with its last frame given: at a border (valley_frame >= 0 for a valley, the
  /// border itself for a passage) or at the newest frame (-1, a flush). The next place begins at
  /// next_start_frame, on the doorway passage next_start_passage_s (NaN: on none).
  SegmentedPlace closePlace(std::int64_t valley_frame, std::int64_t last_frame_of_place, double last_time_s,
                            std::int64_t next_start_frame, double next_start_time_s, double next_start_passage_s);

  FiedlerSegmenterConfig config_;
  const SimilarityMeasure& similarity_;
  ValleyDetector detector_;

  // Ring window: slot s holds frame slot_frame_[s]; next_slot_ is where the next frame goes; the window
  // is the count_ slots before it (oldest first), so evicting the oldest frame is --count_.
  int count_ = 0;
  bool window_full_ = false;
  int next_slot_ = 0;
  std::vector<std::shared_ptr<const Fingerprint>> slot_fingerprint_;
  std::vector<std::int64_t> slot_frame_;
  std::vector<double> slot_time_;
  std::vector<double> slot_distance_;  ///< metres travelled at the frame; NaN = motion unknown
  Eigen::MatrixXd affinity_;  ///< n x n, symmetric, zero diagonal; rows of empty slots are 0
  Eigen::VectorXd degree_;    ///< n
  Eigen::VectorXd inv_sqrt_degree_;
  Eigen::MatrixXd laplacian_;  ///< n x n scratch, window order (top-left count_ x count_)
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver_;

  std::int64_t last_frame_ = -1;
  double last_time_s_ = 0.0;
  double last_added_distance_m_ = std::numeric_limits<double>::quiet_NaN();
  double last_added_turned_rad_ = 0.0;
  std::int64_t place_start_ = -1;
  double place_start_time_s_ = 0.0;
  // Representative candidates of the open place (and of frames after a pending border), in
  // insertion order; one record per distinct frame.
  std::vector<Candidate> candidates_;
  // The border the detector's current minimum would produce: recorded when the minimum was recorded.
  std::int64_t pending_min_frame_ = -1;     ///< detector minimum this border belongs to
  std::int64_t pending_border_frame_ = -1;  ///< first frame of the next place; -1 = not known yet
  double pending_border_time_s_ = 0.0;
  std::int64_t pending_last_frame_ = -1;  ///< last frame of the closing place at that border
  double pending_last_time_s_ = 0.0;
  // PlaceMedoid: samples of the open place (and of frames after a pending border), in frame order, with
  // their pairwise similarities in the top-left corner of place_sample_affinity_ (allocated once).
  std::vector<Candidate> place_samples_;
  Eigen::MatrixXd place_sample_affinity_;
  double sample_interval_s_ = 0.0;     ///< the current sampling interval (doubles when thinned)
  std::int64_t sample_stride_ = 1;     ///< ... and in frames (doubles when thinned)
  // place_samples > 0: the open place's samples (and those after a pending border), in frame order,
  // at most kMaxPlaceSamples (every other one dropped and the interval doubled when full).
  std::vector<Candidate> query_samples_;
  double query_sample_interval_s_ = 0.0;
  double last_query_sample_s_ = -std::numeric_limits<double>::infinity();
  std::int64_t kept_places_ = 0;
  std::int64_t dropped_places_ = 0;
  std::int64_t ignored_valleys_ = 0;
  std::int64_t skipped_frames_ = 0;
  std::int64_t thinned_frames_ = 0;
  // doorway_shift_s: the passages, and the recent frames (ring, oldest at recent_next_ once full) to
  // find the frame a passage time falls on.
  DoorwayPassageDetector doorway_;
  std::vector<std::int64_t> recent_frame_;
  std::vector<double> recent_time_;
  std::size_t recent_next_ = 0;
  std::size_t recent_count_ = 0;
  std::int64_t doorway_shifts_ = 0;
  std::int64_t doorway_repeats_ = 0;
  std::int64_t doorway_borders_ = 0;
  std::int64_t interrupted_valleys_ = 0;
  /// Passages up to this time are handled (reached by the frames); -inf: none yet.
  double passages_done_s_ = -std::numeric_limits<double>::infinity();
  /// The passage the open place began at (NaN: it began at no passage).
  double place_start_passage_s_ = std::numeric_limits<double>::quiet_NaN();
  /// The passage moveBorderToDoorway moved the pending border to (NaN: not moved).
  double pending_border_passage_s_ = std::numeric_limits<double>::quiet_NaN();
  // After a doorway shift, the representative is chosen among frames inside the borders found by
  // appearance: [representative_from_, representative_last_] of the open place.
  std::int64_t representative_from_ = -1;
  std::int64_t representative_last_ = std::numeric_limits<std::int64_t>::max();
  std::int64_t next_representative_from_ = -1;
};

}  // namespace toposlam
