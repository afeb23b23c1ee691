// FrameTimeline: a source's frame timestamps made into a clock that never goes back (issue 19; the
// decisions are in docs/reliability.md, "Clock jumps").
//
// The segmentation window is measured in seconds of the frames' own timestamps. Those can go back: a
// recording made with a wall clock that NTP stepped (a robot without a real-time clock), a video with
// broken PTS, a timestamps.csv written across such a step. Taken as they are, a step back of 30 s keeps
// every frame in the window until the ring's size evicts it (one place of 80 frames where there were
// three); and a clock that only refuses to go back (each such frame "one second later") turns a window in
// seconds into a window in frames for good, since the frames then never catch up with their own clock.
//
// So a frame whose timestamp goes back (or repeats, or is not a number) is placed one typical frame
// interval after the previous frame (the lower median of the last kIntervals intervals; 1 s before there is
// one, as for a folder without timestamps), and the frames after it keep their source's spacing from
// there: the step is cut out and nothing else changes. A jump forward is kept as it is: it cannot be told
// from a gap (the camera away while the robot moved on), and after a gap the window must forget the old
// frames.
//
// Pure: no clock, no I/O, no allocation; one instance per source (a new traversal starts a new one).
// Not thread-safe.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

namespace toposlam {

class FrameTimeline {
 public:
  /// Intervals the typical one is the median of.
  static constexpr int kIntervals = 8;

  /// The next frame's time on the timeline, seconds: `source_time_s` (any value, NaN included) plus the
  /// steps cut out so far. Strictly greater than the previous frame's.
  double place(double source_time_s);

  /// Frames whose source time went back (by any amount), and the size of the last such step, seconds.
  std::int64_t stepsBack() const { return steps_back_; }
  double lastStepBackS() const { return last_step_back_s_; }
  /// Frames whose source time repeated the previous one or was not finite.
  std::int64_t repeated() const { return repeated_; }
  /// Seconds the timeline runs ahead of the source's own clock now (0 until a step back or a repeat).
  double offsetS() const { return offset_s_; }
  /// The lower median of the last kIntervals intervals between placed frames (a gap among them weighs
  /// little); 1 s before the second frame.
  double typicalIntervalS() const;

 private:
  double offset_s_ = 0.0;
  double last_s_ = std::numeric_limits<double>::quiet_NaN();  ///< the previous frame's placed time
  std::array<double, kIntervals> intervals_{};                ///< ring of recent intervals, seconds
  int interval_count_ = 0;
  int next_interval_ = 0;
  std::int64_t steps_back_ = 0;
  std::int64_t repeated_ = 0;
  double last_step_back_s_ = 0.0;
};

}  // namespace toposlam
