// Pure evaluation measures against ground truth (docs/evaluation.md gives the exact definitions):
//   - localisation (thesis Table 3.1): per probability threshold, images at or above it and precision;
//   - loop closure: precision-recall over frame pairs, recall at 100 % precision;
//   - segmentation: place boundaries vs. room changes within a tolerance of k frames (precision, recall,
//     F1), places per traversal, consistency of places across traversals;
//   - topology: nodes matching rooms one-to-one, merged nodes, split rooms, right/wrong/missed loop
//     closures.
// No I/O: inputs are plain vectors, so every measure is unit-tested with hand-made answers.
// Thread-safety: pure functions.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "toposlam/eval/ground_truth.hpp"

namespace toposlam::eval {

// ---- localisation (Table 3.1) ----

struct LocalisationPrediction {
  std::string predicted;  ///< predicted place label
  std::string truth;      ///< ground-truth place label
  double probability = 0.0;
};

struct LocalisationRow {
  double threshold = 0.0;
  int images = 0;          ///< predictions with probability >= threshold
  int correct = 0;         ///< of those, predicted == truth
  double precision = 0.0;  ///< correct / images; NaN when images == 0
};

/// The thesis' default thresholds 0.5, 0.6, 0.7, 0.8, 0.9.
std::vector<double> defaultThresholds();
std::vector<LocalisationRow> localisationTable(const std::vector<LocalisationPrediction>& predictions,
                                               const std::vector<double>& thresholds);

// ---- loop closure ----

/// Per frame pair (i, j): 1 same place (positive), 0 different (negative), -1 not evaluated.
struct LoopClosureTruth {
  int size = 0;
  std::vector<std::int8_t> state;  ///< size*size, symmetric
  std::int8_t at(int i, int j) const {
    return state[static_cast<std::size_t>(i) * static_cast<std::size_t>(size) + static_cast<std::size_t>(j)];
  }
  void set(int i, int j, std::int8_t s);  ///< sets (i,j) and (j,i)
  std::int64_t positives() const;         ///< unordered pairs i > j with state 1
};

/// From a matrix like samples_GT.bmp: pairs with |i - j| <= min_gap are not evaluated (the matrix marks
/// revisits only, not a frame's neighbours); the diagonal never is.
LoopClosureTruth truthFromMatrix(const LoopClosureMatrix& matrix, int min_gap);
/// From per-frame rooms (-1 = doorway): positive when both frames are in the same room on different
/// visits (a visit = a maximal run of one room, doorway frames ignored in between), negative when the rooms
/// differ; pairs within one visit, with a doorway frame or with |i - j| <= min_gap are not evaluated.
LoopClosureTruth truthFromRooms(const std::vector<int>& rooms, int min_gap);

struct ScoredPair {
  int i = 0, j = 0;  ///< frames, i > j
  double score = 0.0;
};

/// Visit number per frame of a label sequence (rooms or nodes): a visit is a maximal run of one label
/// >= 0, frames labelled -1 ignored in between (they get -1 and neither end nor start a visit).
std::vector<int> visitIds(const std::vector<int>& labels);

/// Predicted loop closures from frame -> node assignments: every pair of frames on the same node (>= 0)
/// in different visits of it (visitIds of node_of_frame), score = the later frame's node probability.
/// Pairs within one visit (one place, or consecutive places kept on one node) are no loop closure: the
/// robot never left, so nothing was recognised.
std::vector<ScoredPair> pairsFromAssignments(const std::vector<int>& node_of_frame,
                                             const std::vector<double>& probability_of_frame);

struct PrPoint {
  double threshold = 0.0;  ///< pairs with score >= threshold are predicted positive
  std::int64_t true_positives = 0, false_positives = 0;
  double precision = 0.0, recall = 0.0;
};

struct PrCurve {
  std::int64_t positives = 0;             ///< ground-truth positive pairs that are evaluated
  std::int64_t predicted = 0;             ///< predicted pairs that are evaluated (state != -1)
  std::vector<PrPoint> points;            ///< one per distinct score, descending threshold
  double recall_at_full_precision = 0.0;  ///< largest recall with no false positive (0 if none)
  double threshold_at_full_precision = 0.0;
  double average_precision = 0.0;  ///< sum over points of (recall step) x precision
};

/// Scores outside the truth matrix throw std::out_of_range; pairs with state -1 are skipped.
PrCurve precisionRecall(const LoopClosureTruth& truth, const std::vector<ScoredPair>& pairs);

// ---- segmentation ----

/// A ground-truth boundary: a cut anywhere in [from, to] is right (cut b = between frames b-1 and b).
/// A direct room change at frame f gives [f, f]; a doorway run d0..d1 between two rooms gives [d0, d1+1].
struct BoundaryInterval {
  std::int64_t from = 0, to = 0;
};

/// Room changes of `rooms`; no boundary is reported at a traversal start (frames in `traversal_starts`),
/// and runs of -1 between the same room are no boundary.
std::vector<BoundaryInterval> roomBoundaries(const std::vector<int>& rooms,
                                             const std::vector<std::int64_t>& traversal_starts);

struct BoundaryScore {
  int tolerance = 0;
  int predicted = 0, truth = 0, matched = 0;
  double precision = 0.0, recall = 0.0, f1 = 0.0;  ///< NaN when undefined (0/0)
  /// Mean signed distance, frames, of matched cuts from their interval (negative = cut before the room
  /// change, e.g. a frontal camera seeing the next room early); NaN when nothing matched.
  double mean_offset = 0.0;
};

/// One-to-one matching (closest first) of predicted cuts to ground-truth intervals within `tolerance` frames.
BoundaryScore scoreBoundaries(const std::vector<std::int64_t>& predicted_cuts,
                              const std::vector<BoundaryInterval>& truth, int tolerance);

/// Traversal t covers frames [starts[t], starts[t+1]) (the last one up to frame_count).
int traversalOf(std::int64_t frame, const std::vector<std::int64_t>& traversal_starts);

struct TraversalCount {
  int traversal = 0;
  int places = 0;       ///< kept places whose representative lies in the traversal
  int room_visits = 0;  ///< ground-truth room visits (runs of one room, doorways ignored)
};

std::vector<TraversalCount> placesPerTraversal(const std::vector<std::int64_t>& representatives,
                                               const std::vector<int>& rooms,
                                               const std::vector<std::int64_t>& traversal_starts);

struct RoomConsistency {
  int room = 0;
  std::vector<int> visits;  ///< per traversal
  std::vector<int> places;  ///< per traversal: kept places whose representative is in this room
};

struct ConsistencyScore {
  std::vector<RoomConsistency> rooms;
  int eligible = 0;    ///< rooms visited in every traversal that yield a place in at least one
  int consistent = 0;  ///< of those, rooms yielding a place in every traversal
  double rate = 0.0;   ///< consistent / eligible; NaN when eligible == 0
};

ConsistencyScore crossTraversalConsistency(const std::vector<std::int64_t>& representatives,
                                           const std::vector<int>& rooms,
                                           const std::vector<std::int64_t>& traversal_starts);

// ---- topology ----

struct TopologyScore {
  int nodes = 0;                ///< distinct nodes among the places
  int rooms = 0;                ///< distinct rooms among the places (room >= 0)
  int one_to_one = 0;           ///< nodes whose places are all in one room that no other node has
  int merged_nodes = 0;         ///< nodes whose places span >= 2 rooms
  int split_rooms = 0;          ///< rooms whose places are spread over >= 2 nodes
  int loop_closures = 0;        ///< places assigned to a node seen before, other than the previous place's
  int wrong_loop_closures = 0;  ///< of those, the place's room is none of the node's earlier places' rooms
  int missed_loop_closures =
      0;  ///< places on a new node whose room was seen before (not just at the previous place)
};

/// place_node[k], place_room[k]: the node and ground-truth room of place k in detection order (room -1 =
/// unknown; such places count for nodes but not for rooms or closures).
TopologyScore scoreTopology(const std::vector<int>& place_node, const std::vector<int>& place_room);

/// A camera pose of the ground truth (the simulator's labels.csv x, y, heading), NaN when unknown.
struct GroundPose {
  double x = std::numeric_limits<double>::quiet_NaN();
  double y = std::numeric_limits<double>::quiet_NaN();
  double heading = std::numeric_limits<double>::quiet_NaN();  ///< radians
};

/// One place of a run: its frames [first, last] and its node in the most probable topology.
struct PlaceSpan {
  std::int64_t first = 0, last = 0;
  int node = -1;
};

/// Place-level loop closures judged by where the camera was, not by room labels (docs/evaluation.md,
/// "Place revisits by pose"): place j covers a frame f of place k when one of j's frames was taken within
/// radius_m of f's position looking within max_heading_rad of its heading; place k revisits the earlier
/// places (other than k - 1) that cover at least min_overlap of its frames.
struct PlaceRevisitScore {
  int places = 0;              ///< places with a node
  int revisits = 0;            ///< places that revisit an earlier place
  int closed_right = 0;        ///< revisits on a node of a place they revisit
  int missed = 0;              ///< revisits on a new node
  int merged_with_previous = 0;  ///< revisits left on the previous place's node, which they do not revisit
  int wrong_closures = 0;      ///< places on an earlier node (not the previous place's) none of whose places they revisit
  double radius_m = 0, max_heading_rad = 0, min_overlap = 0;
  bool by_pose = true;    ///< false: judged by a loop-closure matrix or room labels (radius and heading unused)
  bool by_rooms = false;  ///< judged by room labels: a frame shows what every frame of its room shows
};

/// place spans in time order; poses[f] for every frame (NaN: unknown, never covers nor counts).
PlaceRevisitScore scorePlaceRevisits(const std::vector<PlaceSpan>& places, const std::vector<GroundPose>& poses,
                                     double radius_m = 1.0, double max_heading_rad = 0.7853981633974483,
                                     double min_overlap = 0.3);

/// Each frame's published earlier frame judged by where the camera was (docs/evaluation.md, "Frame matches by
/// pose"): right when it was taken within radius_m of the frame's position looking within max_heading_rad
/// of its heading. A match to or from a frame of unknown pose is not counted.
struct FrameMatchPoseScore {
  std::int64_t matches = 0, right = 0, wrong = 0;
  double radius_m = 0, max_heading_rad = 0;
};

/// match[f]: frame f's matched earlier frame (-1: none); poses[f] for every frame.
FrameMatchPoseScore scoreFrameMatchesByPose(const std::vector<std::int64_t>& match, const std::vector<GroundPose>& poses,
                                            double radius_m = 2.0, double max_heading_rad = 1.0);

/// The same counts judged by a loop-closure matrix (a real set's ground truth): place j covers a frame f of
/// place k when one of j's frames shows the same place as f (same.at(f, g)). same.size = the run's frames.
PlaceRevisitScore scorePlaceRevisits(const std::vector<PlaceSpan>& places, const LoopClosureMatrix& same,
                                     double min_overlap = 0.3);

/// The same counts judged by room labels (rooms[f] for every frame, -1: unknown, shows nothing): frames of
/// one room show the same place. Room labels cannot tell a room's other corner from a revisit, so with rooms
/// as large as a building's floor only the wrong closures (to a place of another room) are sharp.
PlaceRevisitScore scorePlaceRevisits(const std::vector<PlaceSpan>& places, const std::vector<int>& rooms,
                                     double min_overlap = 0.3);

/// The most frequent value >= 0 among values (smallest on ties), -1 when none.
int majority(const std::vector<int>& values);

}  // namespace toposlam::eval
