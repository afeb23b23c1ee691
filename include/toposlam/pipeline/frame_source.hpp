// Frames enter toposlam through one interface, whatever produced them: an image folder, a video file,
// the simulated world, a V4L2 or libcamera camera. Sources are opened by URI (see openFrameSource).
//
// Two ways to read: next() blocks until a frame or the end (offline tools); nextFor() waits at most
// about a given time, so a real-time consumer (the pipeline's capture thread) keeps beating its
// heartbeat and noticing a stop while a camera is silent or being reconnected. interrupt() makes a
// blocked or future read end promptly, from any thread. state() says what a live source is doing
// (streaming or reconnecting, and its counters), from any thread.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

namespace toposlam {

struct Frame {
  cv::Mat image;  ///< CV_8UC3, BGR (CV_8UC1 from a grey camera). May view a driver
                  ///< buffer held by `buffer_lease`.
  /// The camera's own grey when it has one (a YUYV camera's luma; a grey camera's `image`), used for
  /// edges and keypoints instead of converting `image`; empty: convert.
  cv::Mat grey;
  std::int64_t sequence = 0;      ///< frame number from the source, from 0; gaps mean dropped frames
  double timestamp_s = 0.0;       ///< capture time in seconds (source clock: monotonic or recorded)
  std::string name;               ///< e.g. the file name, for reports; may be empty
  /// Keeps a zero-copy buffer alive; releasing it hands the buffer back to the source.
  std::shared_ptr<void> buffer_lease;
};

/// Why a source skipped a frame (status_t's source_skipped_<reason>, docs/daemon.md).
enum class SkipReason {
  Unreadable,   ///< a file that cannot be opened or read (permissions, a folder, an I/O error)
  Truncated,    ///< an empty or cut-short file (no end marker), a camera buffer shorter than the image
  Corrupt,      ///< the decoder refused it or reported corrupt data (a damaged JPEG, an undecodable MJPEG)
  TooLarge,     ///< over the pixel cap (max_pixels) or the file-size cap; not decoded
  WrongFormat,  ///< a frame of an unexpected pixel type or size from a video or a camera
  DeviceError,  ///< the driver or camera flagged the buffer as failed
  Other,        ///< a source that does not tell why (a plug-in source)
};
inline constexpr std::size_t kSkipReasonCount = 7;
inline const char* toString(SkipReason reason) {
  static constexpr const char* kNames[kSkipReasonCount] = {
      "unreadable", "truncated", "corrupt", "too large", "wrong format", "device error", "other"};
  return kNames[static_cast<std::size_t>(reason)];
}

/// Frames a source skipped, counted by reason. A plain value.
struct SkippedFrames {
  std::array<std::int64_t, kSkipReasonCount> count{};
  std::int64_t& operator[](SkipReason reason) { return count[static_cast<std::size_t>(reason)]; }
  std::int64_t operator[](SkipReason reason) const { return count[static_cast<std::size_t>(reason)]; }
  std::int64_t total() const {
    std::int64_t sum = 0;
    for (std::int64_t n : count) sum += n;
    return sum;
  }
};

/// The skipped part of a status line: "skipped 12 frames (truncated 10, corrupt 2)", reasons with a count in
/// SkipReason's order; "" when none was skipped.
inline std::string skippedFramesText(const SkippedFrames& skipped) {
  if (skipped.total() == 0) return "";
  std::string text =
      "skipped " + std::to_string(skipped.total()) + (skipped.total() == 1 ? " frame (" : " frames (");
  bool first = true;
  for (std::size_t r = 0; r < kSkipReasonCount; ++r) {
    if (skipped.count[r] == 0) continue;
    text += (first ? "" : ", ") + std::string(toString(static_cast<SkipReason>(r))) + " " +
            std::to_string(skipped.count[r]);
    first = false;
  }
  return text + ")";
}

/// Unrecoverable source failures (cannot open, unsupported format, device gone for good).
class FrameSourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Outcome of FrameSource::nextFor().
enum class SourceWait {
  Frame,    ///< a frame was returned
  Timeout,  ///< no frame within the time (camera silent, reconnecting, a bad frame skipped): call again
  End,      ///< end of the stream, or interrupt() was called: no more frames
};

/// Whether a live source is delivering or trying to get its camera back.
enum class SourceLink { Streaming, Reconnecting };

inline const char* toString(SourceLink link) {
  return link == SourceLink::Reconnecting ? "reconnecting" : "streaming";
}

/// What a source reads from: the status says "camera streaming" only for a camera.
enum class SourceKind { Camera, Simulator, ImageFiles, VideoFile };

/// What the status says a source is doing: "camera streaming", "camera reconnecting", "simulator running",
/// "reading images", "reading a video file".
inline const char* sourceActivityText(SourceKind kind, SourceLink link) {
  switch (kind) {
    case SourceKind::Simulator:
      return "simulator running";
    case SourceKind::ImageFiles:
      return "reading images";
    case SourceKind::VideoFile:
      return "reading a video file";
    case SourceKind::Camera:
      break;
  }
  return link == SourceLink::Reconnecting ? "camera reconnecting" : "camera streaming";
}

/// The status message's source_state (status_t.lcm): a camera's link ("streaming", "reconnecting"), else
/// what the source is ("simulator", "images", "video").
inline const char* sourceStateName(SourceKind kind, SourceLink link) {
  switch (kind) {
    case SourceKind::Simulator:
      return "simulator";
    case SourceKind::ImageFiles:
      return "images";
    case SourceKind::VideoFile:
      return "video";
    case SourceKind::Camera:
      break;
  }
  return toString(link);
}

/// A snapshot of what a source is doing (no strings: read on the frame path).
struct FrameSourceState {
  SourceKind kind = SourceKind::Camera;  ///< sources other than cameras say what they are
  SourceLink link = SourceLink::Streaming;
  std::int64_t reconnects = 0;   ///< outages survived (successful reopenings)
  int reconnect_attempts = 0;    ///< failed attempts in the current outage
  std::int64_t dropped = 0;      ///< frames lost according to the driver's sequence gaps

  /// The state of a source that is no camera: always delivering, nothing to reconnect.
  static FrameSourceState of(SourceKind kind) {
    FrameSourceState state;
    state.kind = kind;
    return state;
  }
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// Human-readable description, e.g. "images:/data/run1 (84 frames)".
  virtual std::string describe() const = 0;
  /// Next frame, or std::nullopt at the end of the stream (or after interrupt()). A single bad frame
  /// (corrupt file, decode failure) is skipped and counted, not thrown; FrameSourceError means the
  /// source cannot go on.
  virtual std::optional<Frame> next() = 0;
  /// Like next() but returns within about `timeout` (plus the time of one non-blocking driver call or
  /// one file decode). The default suits sources whose next() never waits long (files, sim).
  virtual SourceWait nextFor(std::chrono::milliseconds timeout, Frame& out) {
    (void)timeout;
    std::optional<Frame> frame = next();
    if (!frame) return SourceWait::End;
    out = std::move(*frame);
    return SourceWait::Frame;
  }
  /// Makes a blocked or future next()/nextFor() end promptly (std::nullopt / End). Thread-safe: any
  /// thread, any number of times.
  virtual void interrupt() = 0;
  /// What the source is doing now. Thread-safe: any thread.
  virtual FrameSourceState state() const { return {}; }
  /// Frames skipped because they were bad (corrupt, truncated, failed to decode).
  virtual std::int64_t skippedFrames() const { return 0; }
  /// The same frames by reason (total() == skippedFrames()). Same thread-safety as skippedFrames(). The
  /// default, for a source that does not tell why: all of them under Other.
  virtual SkippedFrames skippedByReason() const {
    SkippedFrames skipped;
    skipped[SkipReason::Other] = skippedFrames();
    return skipped;
  }
  /// True when frames come at the world's pace whatever the consumer does: a camera, or a file source
  /// played in real time (?rate=). False for files and the simulator read as fast as they are asked for.
  /// (What a full pipeline queue does by default: drop the oldest frame, or wait; QueueOverflow::Auto.)
  virtual bool realTime() const { return false; }
  /// Total frames if known in advance (files), else -1 (cameras).
  virtual std::int64_t frameCountHint() const { return -1; }
  /// The name of frame `sequence` when the source can tell it without reading the frame (files: the file
  /// name), else "" (cameras, the simulator). Thread-safe: any thread (a map snapshot records the name of the
  /// last frame it holds, so that a restart continues after it: continueAfter()).
  virtual std::string frameName(std::int64_t sequence) const {
    (void)sequence;
    return {};
  }
  /// Continues the stream after the frame `last_sequence` named `last_name` (the last frame a resumed map
  /// holds): the frames up to it are skipped unread. Returns the sequence of the next frame (the frame count
  /// when none is left), or std::nullopt when the source cannot (live sources) or has no such frame (another
  /// folder under the same name): it then starts from its first frame. Call before the first next().
  virtual std::optional<std::int64_t> continueAfter(std::int64_t last_sequence, const std::string& last_name) {
    (void)last_sequence;
    (void)last_name;
    return std::nullopt;
  }
};

}  // namespace toposlam
