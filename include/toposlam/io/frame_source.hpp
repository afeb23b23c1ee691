// Frames enter toposlam through one interface, whatever produced them: an image folder, a video file,
// the simulated world, a V4L2 or libcamera camera. Sources are opened by URI (see openFrameSource).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

namespace toposlam {

struct Frame {
  cv::Mat image;                  ///< CV_8UC3, BGR. May view a driver buffer held by `buffer_lease`.
  std::int64_t sequence = 0;      ///< frame number from the source, from 0; gaps mean dropped frames
  double timestamp_s = 0.0;       ///< capture time in seconds (source clock: monotonic or recorded)
  std::string name;               ///< e.g. the file name, for reports; may be empty
  /// Keeps a zero-copy buffer alive; releasing it hands the buffer back to the source.
  std::shared_ptr<void> buffer_lease;
};

/// Unrecoverable source failures (cannot open, unsupported format, device gone for good).
class FrameSourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// Human-readable description, e.g. "images:/data/run1 (84 frames)".
  virtual std::string describe() const = 0;
  /// Next frame, or std::nullopt at the end of the stream. A single bad frame (corrupt file, decode
  /// failure) is skipped and counted, not thrown; FrameSourceError means the source cannot go on.
  virtual std::optional<Frame> next() = 0;
  /// Frames skipped because they were bad (corrupt, truncated, failed to decode).
  virtual std::int64_t skippedFrames() const { return 0; }
  /// Total frames if known in advance (files), else -1 (cameras).
  virtual std::int64_t frameCountHint() const { return -1; }
};

}  // namespace toposlam
