// When does the robot pass through a doorway? Predicted from the vertical edges of successive frames
// (docs/segmentation.md, "Borders at doorways").
//
// A place border found by appearance (the lambda2 valley and its best split) falls where the view
// changes, which is where the robot turns towards a door or away from it, about a metre from the
// doorway. The doorway itself shows in the VPACK edges: its two jambs are strong vertical edges, one
// left and one right of the image centre, that move apart as the robot drives towards them and leave
// the image just before it passes. For an edge at lateral offset a and depth d, seen by a camera
// moving along its axis at speed v, the image offset from the centre is x = f a / d, so 1 / x =
// (d0 - v t) / (f a) falls linearly in time and reaches 0 when the robot is level with the edge: a
// line fitted to 1 / |x| over the edge's last frames predicts that moment (its time to contact) from
// the image alone, with no calibration and no odometry.
//
// This class tracks every edge outwards from frame to frame (the same side of the centre, moving out by
// a bounded step), and when a track ends at the image border it predicts the track's passage time. A
// left and a right track whose predictions agree are a doorway passage, recorded with the mean of the
// two. FiedlerSegmenter moves a border to the passage nearest it (within a few seconds), so the place
// changes where the robot crosses the doorway; it never adds or removes a border.
//
// Plain and deterministic: no clocks (times are the frames' own), no threads. Storage is fixed at
// construction; addFrame() does not allocate. Not thread-safe.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace toposlam {

struct DoorwayPassageConfig {
  /// A track needs this many frames (the fit's points) to predict a passage.
  int min_track_frames = 3;
  /// The line is fitted to a track's frames of its last fit_s seconds (at least min_track_frames of
  /// them, at most kFitPoints): the jambs' last moments before they leave the view, not the turn before.
  double fit_s = 0.6;
  /// A track ends "at the border" when its last edge is this far out: a fraction of the half-width.
  double border_fraction = 0.85;
  /// From one frame to the next an edge may move out by at most this factor of its offset, plus
  /// `step_fraction` of the half-width (it may move in by `step_fraction / 4` of the half-width: jitter).
  double max_growth = 1.6;
  double step_fraction = 0.06;
  /// A track whose edge moves out is continued only by an edge that moves out by at least this fraction
  /// of the track's mean outward speed over its last `fit_s` (less the inward jitter). When the jamb
  /// leaves the view, a far edge standing near the border would otherwise continue its track, and its
  /// slow drift predicts the passage seconds late (docs/segmentation.md, "Jamb tracks taken over by a
  /// far edge"). 0 turns the check off.
  double min_outward_speed_fraction = 0.4;
  /// A passage predicted further ahead than this (seconds after the track's last frame) is ignored: an
  /// edge far away that merely drifts out.
  double max_lookahead_s = 3.0;
  /// A left and a right prediction agree when they differ by at most this (seconds; at least two frame
  /// intervals) ...
  double pair_tolerance_s = 0.8;
  /// ... or by at most this fraction of the time still to go from the later track's last frame.
  double pair_tolerance_fraction = 0.5;
  /// ... and their tracks left the image at most this far apart (seconds): both jambs of a doorway pass
  /// out of view together, two edges that merely happen to predict the same moment seldom do.
  double max_exit_gap_s = 0.5;
  /// Frames further apart than this (seconds: frames left out while the robot stood, a capture stall)
  /// end every track, and a passage predicted after the frame before the gap is forgotten: an edge cannot
  /// be followed across the gap, and the robot did not keep going at the speed the prediction assumed.
  double max_frame_gap_s = 1.5;
  /// Returns "" when valid, else "<field>: <problem, allowed range>".
  std::string validate() const;
};

class DoorwayPassageDetector {
 public:
  static constexpr int kMaxTracks = 64;     ///< edges followed at once; more edges in a frame are ignored
  static constexpr int kFitPoints = 32;     ///< the last frames of a track kept for the fit
  static constexpr int kMaxExits = 16;      ///< recent track ends waiting for a partner
  static constexpr int kMaxPassages = 32;   ///< passages remembered (the oldest go first)
  static constexpr int kMaxEdges = 256;     ///< edges of one frame looked at (the rest are ignored)

  /// Throws std::invalid_argument on an invalid config.
  explicit DoorwayPassageDetector(const DoorwayPassageConfig& config = {});

  /// The next frame: its time (seconds, increasing), its width in pixels and its vertical edges
  /// (ascending columns, as Fingerprint::edge_columns). A time that does not increase starts afresh
  /// (a new traversal): every track, pending track end and passage is forgotten.
  void addFrame(double time_s, int image_width, const std::vector<int>& edge_columns);

  /// The recorded passage nearest to `time_s` and at most `max_distance_s` from it; none when there is
  /// none. Ties go to the earlier passage.
  std::optional<double> nearestPassage(double time_s, double max_distance_s) const;

  /// Passages recorded so far (including those no longer remembered).
  std::int64_t passageCount() const { return passage_count_; }
  /// The earliest remembered passage later than `after_s`; none when there is none.
  std::optional<double> firstPassageAfter(double after_s) const;

 private:
  struct Track {
    std::array<double, kFitPoints> time{};
    std::array<double, kFitPoints> offset{};  ///< |column - centre|, pixels; newest at (count - 1) % kFitPoints
    int count = 0;
    int side = 0;              ///< -1 left of the centre, +1 right
    double first_offset = 0.0; ///< |column - centre| where the track began
    double lastOffset() const { return offset[static_cast<std::size_t>((count - 1) % kFitPoints)]; }
    double lastTime() const { return time[static_cast<std::size_t>((count - 1) % kFitPoints)]; }
  };
  struct Exit {
    double passage_s;
    double last_s;
    int side;
  };
  /// How many of the track's newest points lie within fit_s of its last one (at least `at_least`, at
  /// most the points kept): the points a fit or a speed is taken over.
  int recentPoints(const Track& track, int at_least) const;
  /// The least outward step (pixels) an edge at time_s must make to continue the track: the jitter
  /// allowance, raised by min_outward_speed_fraction of the track's recent outward speed.
  double minContinuationGrowth(const Track& track, double time_s, double step) const;
  /// A track that ended: records its predicted passage when it ended at the border.
  void endTrack(const Track& track, double half_width);
  void recordPassage(double passage_s);

  DoorwayPassageConfig config_;
  std::vector<Track> tracks_, next_tracks_;
  std::vector<char> edge_used_;
  std::vector<Exit> exits_;
  std::vector<double> passages_;  ///< ascending
  double last_time_s_ = 0.0;
  double frame_interval_s_ = 0.0;  ///< between the last two frames
  bool started_ = false;
  std::int64_t passage_count_ = 0;
};

}  // namespace toposlam
