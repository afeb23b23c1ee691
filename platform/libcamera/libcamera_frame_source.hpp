// libcamera camera frames: `libcamera:ID?size=WxH&buffers=N` (ID as `cam --list` prints it; an empty
// ID picks the first camera). Optional at build time: the library `toposlam_libcamera` exists only when
// pkg-config finds libcamera (Debian 12 ships 0.0.3; newer versions compile too, see the version guards
// in the implementation).
//
// Frames are handed off from libcamera's thread without copying: the completed request's buffer is
// mmap'd once at start, the Frame's image views it (RGB888, which is B,G,R in memory) and the Frame's
// `buffer_lease` re-queues the request when released. Other formats the pipeline may impose (BGR888,
// YUYV, MJPEG) are converted and the request re-queued right away. If the consumer falls behind, the
// oldest completed request is re-queued unseen and counted as dropped (a bounded hand-off queue).
//
// Thread-safety: next()/nextFor() from one thread; interrupt(), state(), the counters and lease releases
// from any.
// libcamera allows one CameraManager per process: sources share one while any is alive.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "toposlam/io/source_uri.hpp"
#include "toposlam/pipeline/frame_source.hpp"

namespace toposlam {

struct LibcameraSourceConfig {
  std::string camera_id;  ///< empty: the first camera libcamera lists
  int width = 640;        ///< requested size in pixels; libcamera may adjust it (then used)
  int height = 480;
  int buffer_count = 4;    ///< requests in flight, 2..16
  int queue_capacity = 2;  ///< completed requests waiting for next(), 1..8; older ones are dropped
  int timeout_ms = 5000;   ///< next() throws FrameSourceError when no frame came for this long

  /// "" or "<key>: <problem, allowed range>".
  std::string validate() const;
};

/// Parses "libcamera:ID?size=WxH&buffers=N" (`rate` is the factory's common key). Throws
/// FrameSourceError naming the key, the bad value and the allowed range, or listing the allowed keys.
LibcameraSourceConfig parseLibcameraUri(const SourceUri& uri);
LibcameraSourceConfig parseLibcameraUri(const std::string& uri);

/// Registers the `libcamera:` scheme with openFrameSource() (io/source_factory.hpp). Call once at start-up.
void registerLibcameraFrameSourceScheme();

/// Camera IDs libcamera sees on this machine (starts a camera manager for the call).
std::vector<std::string> listLibcameraCameras();

/// "0.0.3" etc.: the libcamera version toposlam was compiled against.
std::string libcameraVersion();

class LibcameraFrameSource : public FrameSource {
 public:
  /// Starts the camera manager, acquires, configures and starts the camera. FrameSourceError with the
  /// list of available cameras if the ID is unknown (or "no cameras found" if there are none).
  explicit LibcameraFrameSource(LibcameraSourceConfig config);
  ~LibcameraFrameSource() override;
  LibcameraFrameSource(const LibcameraFrameSource&) = delete;
  LibcameraFrameSource& operator=(const LibcameraFrameSource&) = delete;

  std::string describe() const override;
  /// Blocks for the next completed request; std::nullopt after interrupt(). FrameSourceError when no
  /// frame came for timeout_ms.
  std::optional<Frame> next() override;
  /// Waits at most `timeout` (Timeout: call again); throws like next() after timeout_ms without a frame.
  SourceWait nextFor(std::chrono::milliseconds timeout, Frame& out) override;
  void interrupt() override;
  FrameSourceState state() const override;  ///< always streaming; `dropped` = requests re-queued unseen
  bool realTime() const override { return true; }
  std::int64_t skippedFrames() const override;
  /// Requests the camera failed (DeviceError) and buffers that did not convert or decode (Corrupt).
  SkippedFrames skippedByReason() const override;
  std::int64_t droppedFrames() const;

  struct Impl;  // libcamera objects, kept out of this header; shared with frame leases

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace toposlam
