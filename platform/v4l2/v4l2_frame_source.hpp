// V4L2 camera frames: `v4l2:/dev/videoN?size=640x480&fps=30&format=yuyv|mjpeg|grey|bgr24|rgb24`.
//
// Streaming I/O with mmap buffers and no libv4l2 on the frame path: QUERYCAP (device_caps), ENUM_FMT,
// S_FMT (and use what the driver returns), S_PARM, REQBUFS, QUERYBUF + mmap, QBUF, STREAMON, then
// poll + DQBUF per frame. YUYV, GREY and RGB24 are converted to BGR with cv::cvtColor and the buffer is
// re-queued right after the conversion; MJPEG is decoded with cv::imdecode (a failure is skipped and
// counted); BGR24 is handed out without a copy: the Frame's image views the mmap'd buffer and its
// `buffer_lease` re-queues the buffer (QBUF) when the last copy of the lease is released.
//
// Counting: driver sequence gaps are dropped frames (droppedFrames(); the gap right after the first
// buffer of a stream is ignored, as some drivers hand out one stale buffer first); error-flagged, short and
// undecodable buffers are skipped frames (skippedFrames()). Timestamps are the driver's monotonic
// buffer timestamps in seconds (CLOCK_MONOTONIC), or the injected monotonic clock at dequeue time when
// the driver does not stamp buffers with the monotonic clock.
//
// Unplug (POLLERR/POLLHUP from poll, ENODEV or another hard error from an ioctl) closes the device and
// reopens it with exponential backoff; the caller just keeps calling next() or nextFor(). nextFor()
// waits at most its timeout per call (one poll slice or one slice of the backoff), so a real-time
// caller keeps its heartbeat while the camera is silent or away. status() and state() say whether the
// camera is connected or reconnecting and how many attempts were made.
//
// A device node that does not exist at start (ENOENT, ENODEV, ENXIO) fails the constructor, unless
// `wait_at_start` (URI `wait=1`; toposlamd's default, see registerV4l2FrameSourceScheme) is set: then
// the source starts in the reconnecting state and opens the camera when it appears. Other start
// failures (permissions, not a capture device, format not offered) always fail the constructor.
//
// Thread-safety: next()/nextFor() from one thread (the capture thread). status(), state(), interrupt()
// and releasing a Frame's buffer_lease are safe from any thread. Leases may outlive the source.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "toposlam/io/source_uri.hpp"
#include "toposlam/pipeline/frame_source.hpp"
#include "v4l2_device.hpp"

struct v4l2_buffer;  // <linux/videodev2.h>

namespace toposlam {

/// Pixel formats toposlam asks a V4L2 driver for (the `format=` URI parameter).
enum class V4l2PixelFormat { Yuyv, Mjpeg, Grey, Bgr24, Rgb24 };

/// "yuyv", "mjpeg", "grey", "bgr24", "rgb24".
std::string toString(V4l2PixelFormat format);
/// The V4L2 fourcc of a format (V4L2_PIX_FMT_*).
std::uint32_t toFourcc(V4l2PixelFormat format);
/// A fourcc as its four characters, e.g. "YUYV"; unprintable bytes as '?'.
std::string fourccName(std::uint32_t fourcc);

struct V4l2SourceConfig {
  std::string device = "/dev/video0";
  int width = 640;    ///< pixels; the driver may choose another size, which is then used
  int height = 480;   ///< pixels
  double fps = 30.0;  ///< requested frame rate (S_PARM); drivers without it ignore it
  V4l2PixelFormat format = V4l2PixelFormat::Yuyv;
  int buffer_count = 4;            ///< mmap buffers requested (REQBUFS), 2..32
  int poll_timeout_ms = 200;       ///< longest poll() slice; interrupt() is noticed within this time
  int reconnect_initial_ms = 100;  ///< first backoff after an unplug, doubled per failed attempt
  /// Backoff ceiling: a camera plugged back is reopened within this (plus the opening), so the daemon
  /// resumes within 2 s of the device's return (issue 19); an attempt on a missing node costs one open().
  int reconnect_max_ms = 500;
  int reconnect_max_attempts = 0;  ///< give up (FrameSourceError) after this many; 0 = never
  bool wait_at_start = false;      ///< a missing device node at start: reconnect instead of failing

  /// "" or "<key>: <problem, allowed range>".
  std::string validate() const;
};

/// Parses "v4l2:/dev/videoN?size=WxH&fps=F&format=yuyv|mjpeg|grey|bgr24|rgb24&buffers=N&wait=0|1"
/// (all parameters optional; `defaults` fills the rest; `gray` = `grey`; `wait` takes any SourceUri
/// switch: 1|0|true|false|yes|no|on|off; `rate` is the factory's common key). Throws FrameSourceError
/// naming the key, the bad value and the allowed range (SourceUri getters), or listing the allowed keys.
V4l2SourceConfig parseV4l2Uri(const SourceUri& uri, const V4l2SourceConfig& defaults = {});
V4l2SourceConfig parseV4l2Uri(const std::string& uri, const V4l2SourceConfig& defaults = {});

/// Registers the `v4l2:` scheme with openFrameSource() (io/source_factory.hpp). Call once at start-up.
/// `wait_at_start` is the default of the URI's `wait=`: the daemon waits for a missing camera, the
/// command-line tools fail at once.
void registerV4l2FrameSourceScheme(bool wait_at_start = false);

/// What the daemon shows in its status. A consistent snapshot.
struct V4l2SourceStatus {
  bool connected = false;
  bool reconnecting = false;
  int reconnect_attempts = 0;        ///< failed attempts since the current outage began
  std::int64_t reconnects = 0;       ///< outages survived (successful reopenings)
  std::int64_t frames = 0;           ///< frames delivered by next()
  std::int64_t dropped = 0;          ///< frames lost according to driver sequence gaps
  std::int64_t skipped = 0;          ///< error-flagged + short + undecodable buffers
  std::int64_t error_buffers = 0;    ///< buffers with V4L2_BUF_FLAG_ERROR
  std::int64_t short_buffers = 0;    ///< bytesused below the negotiated image size
  std::int64_t decode_failures = 0;  ///< MJPEG buffers cv::imdecode could not decode
  int width = 0;                     ///< negotiated size (pixels)
  int height = 0;
  std::string pixel_format;  ///< negotiated fourcc, e.g. "YUYV"
  double fps = 0.0;          ///< frame rate the driver reported after S_PARM (0 if unknown)
  std::string driver;        ///< QUERYCAP driver name, e.g. "vivid"
  std::string last_error;    ///< why the device was lost or a reopening failed
};

/// Time and waiting, injected so tests run without sleeping.
struct V4l2Runtime {
  /// Monotonic clock in seconds; default CLOCK_MONOTONIC (same clock as V4L2 buffer timestamps).
  std::function<double()> monotonic_s;
  /// Waits before a reconnect attempt (one slice of the backoff); default waits on a condition variable
  /// that interrupt() wakes.
  std::function<void(std::chrono::milliseconds)> sleep;
};

class V4l2FrameSource : public FrameSource {
 public:
  /// Opens and starts the device; throws FrameSourceError with an actionable message if it cannot
  /// (missing node unless wait_at_start, not a capture device, format not offered, no buffers).
  explicit V4l2FrameSource(V4l2SourceConfig config,
                           std::unique_ptr<V4l2Device> device = makeSystemV4l2Device(),
                           V4l2Runtime runtime = {});
  ~V4l2FrameSource() override;
  V4l2FrameSource(const V4l2FrameSource&) = delete;
  V4l2FrameSource& operator=(const V4l2FrameSource&) = delete;

  std::string describe() const override;
  /// Blocks until a frame arrives (reconnecting if needed). std::nullopt only after interrupt().
  /// FrameSourceError when reconnecting gave up (reconnect_max_attempts).
  std::optional<Frame> next() override;
  /// At most one poll slice (min(timeout, poll_timeout_ms)) or one backoff slice per call.
  SourceWait nextFor(std::chrono::milliseconds timeout, Frame& out) override;
  /// Makes a blocked or future next()/nextFor() end (within poll_timeout_ms). Any thread.
  void interrupt() override;
  FrameSourceState state() const override;
  bool realTime() const override { return true; }
  std::int64_t skippedFrames() const override;
  /// Error-flagged buffers (DeviceError), short or empty ones (Truncated), MJPEG that did not decode
  /// (Corrupt).
  SkippedFrames skippedByReason() const override;
  std::int64_t droppedFrames() const;
  V4l2SourceStatus status() const;

  struct Stream;  // the open device, its buffers and the lock shared with leases (implementation)

 private:
  bool start(bool absent_is_ok);         // open + negotiate + stream; false: node absent (and ok)
  void stop();                           // streamoff + close; outstanding leases stay valid
  void lose(const std::string& reason);  // device lost: stop and begin reconnecting
  void reconnectSlice(std::chrono::milliseconds timeout);  // a slice of backoff, then maybe an attempt
  std::optional<Frame> handleBuffer(const ::v4l2_buffer& buffer);
  void requeue(std::uint32_t index);
  void waitFor(std::chrono::milliseconds delay);
  template <typename Update>
  void updateStatus(Update&& update);

  V4l2SourceConfig config_;
  std::shared_ptr<V4l2Device> device_;
  V4l2Runtime runtime_;
  std::shared_ptr<Stream> stream_;  // null while disconnected

  // Negotiated stream (valid while stream_ is set).
  std::uint32_t fourcc_ = 0;
  int width_ = 0;
  int height_ = 0;
  std::uint32_t bytes_per_line_ = 0;
  std::uint32_t size_image_ = 0;

  // Sequence bookkeeping across reconnects.
  bool have_last_driver_sequence_ = false;
  std::uint32_t last_driver_sequence_ = 0;
  std::int64_t stream_sequence_base_ = 0;  // Frame::sequence of the first buffer of this stream
  std::uint32_t first_driver_sequence_ = 0;
  int buffers_this_stream_ = 0;     // buffers dequeued since STREAMON
  std::int64_t next_sequence_ = 0;  // one past the last delivered Frame::sequence

  // Reconnecting: the backoff still to wait before the next attempt (-1: no attempt scheduled yet).
  std::int64_t backoff_left_ms_ = -1;

  mutable std::mutex status_mutex_;
  V4l2SourceStatus status_;
  std::mutex stop_mutex_;
  std::condition_variable stop_cv_;
  std::atomic<bool> stop_requested_{false};
};

}  // namespace toposlam
