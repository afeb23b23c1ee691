// V4l2FrameSource: V4L2 streaming capture with mmap buffers, format negotiation, BGR conversion or
// zero-copy hand-off, drop/skip accounting and reconnect-with-backoff after an unplug.
// See v4l2_frame_source.hpp for the contract and docs/cameras.md for the reasoning.
#include "v4l2_frame_source.hpp"

#include <linux/videodev2.h>
#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <sstream>
#include <tuple>
#include <utility>

#include <spdlog/spdlog.h>
#include <opencv2/core/mat.hpp>

#include "camera_pixels.hpp"

namespace toposlam {

namespace {

std::string errnoText(int error_number) {
  return std::string(std::strerror(error_number)) + " (errno " + std::to_string(error_number) + ")";
}

std::string textOf(const std::uint8_t* bytes, std::size_t capacity) {
  std::size_t length = 0;
  while (length < capacity && bytes[length] != 0) ++length;
  return std::string(bytes, bytes + length);
}

/// The layout of a fourcc toposlam converts (camera_pixels.hpp); nullopt for anything else.
std::optional<CameraPixelLayout> layoutOf(std::uint32_t fourcc) {
  switch (fourcc) {
    case V4L2_PIX_FMT_YUYV:
      return CameraPixelLayout::Yuyv;
    case V4L2_PIX_FMT_GREY:
      return CameraPixelLayout::Grey;
    case V4L2_PIX_FMT_RGB24:
      return CameraPixelLayout::Rgb;
    case V4L2_PIX_FMT_BGR24:
      return CameraPixelLayout::Bgr;
    case V4L2_PIX_FMT_MJPEG:
    case V4L2_PIX_FMT_JPEG:
      return CameraPixelLayout::Jpeg;
    default:
      return std::nullopt;
  }
}

const char* kConvertibleFormats = "yuyv, mjpeg, grey, bgr24, rgb24";

}  // namespace

// ---------------------------------------------------------------------------------------------
// Formats and URI

std::string toString(V4l2PixelFormat format) {
  switch (format) {
    case V4l2PixelFormat::Yuyv:
      return "yuyv";
    case V4l2PixelFormat::Mjpeg:
      return "mjpeg";
    case V4l2PixelFormat::Grey:
      return "grey";
    case V4l2PixelFormat::Bgr24:
      return "bgr24";
    case V4l2PixelFormat::Rgb24:
      return "rgb24";
  }
  return "?";
}

std::uint32_t toFourcc(V4l2PixelFormat format) {
  switch (format) {
    case V4l2PixelFormat::Yuyv:
      return V4L2_PIX_FMT_YUYV;
    case V4l2PixelFormat::Mjpeg:
      return V4L2_PIX_FMT_MJPEG;
    case V4l2PixelFormat::Grey:
      return V4L2_PIX_FMT_GREY;
    case V4l2PixelFormat::Bgr24:
      return V4L2_PIX_FMT_BGR24;
    case V4l2PixelFormat::Rgb24:
      return V4L2_PIX_FMT_RGB24;
  }
  return 0;
}

std::string fourccName(std::uint32_t fourcc) {
  std::string name(4, '?');
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xffU);
    if (c >= 0x20 && c < 0x7f) name[static_cast<std::size_t>(i)] = c;
  }
  while (!name.empty() && name.back() == ' ') name.pop_back();
  return name;
}

std::string V4l2SourceConfig::validate() const {
  if (device.empty()) return "device: must name a device node like /dev/video0";
  if (width < 16 || width > 8192) return "size: width must be in [16, 8192], got " + std::to_string(width);
  if (height < 16 || height > 8192)
    return "size: height must be in [16, 8192], got " + std::to_string(height);
  if (!(fps > 0.0 && fps <= 1000.0)) return "fps: must be in (0, 1000], got " + std::to_string(fps);
  if (buffer_count < 2 || buffer_count > 32)
    return "buffers: must be in [2, 32], got " + std::to_string(buffer_count);
  if (poll_timeout_ms < 1 || poll_timeout_ms > 10000)
    return "poll_timeout_ms: must be in [1, 10000], got " + std::to_string(poll_timeout_ms);
  if (reconnect_initial_ms < 1 || reconnect_initial_ms > 60000)
    return "reconnect_initial_ms: must be in [1, 60000], got " + std::to_string(reconnect_initial_ms);
  if (reconnect_max_ms < reconnect_initial_ms || reconnect_max_ms > 600000)
    return "reconnect_max_ms: must be in [reconnect_initial_ms, 600000], got " +
           std::to_string(reconnect_max_ms);
  if (reconnect_max_attempts < 0)
    return "reconnect_max_attempts: must be >= 0 (0 = retry forever), got " +
           std::to_string(reconnect_max_attempts);
  return "";
}

V4l2SourceConfig parseV4l2Uri(const SourceUri& uri, const V4l2SourceConfig& defaults) {
  if (uri.scheme != "v4l2") throw FrameSourceError("v4l2: URI must start with 'v4l2:', got '" + uri.text + "'");
  if (uri.path.empty() || uri.path.front() != '/' || uri.path.find('?') != std::string::npos)
    throw FrameSourceError("v4l2: expected a device path like v4l2:/dev/video0?size=640x480 (query items are "
                           "key=value), got '" + uri.text + "'");
  uri.requireOnly({"size", "fps", "format", "buffers", "wait"});
  V4l2SourceConfig config = defaults;
  config.device = uri.path;
  std::tie(config.width, config.height) = uri.getSize("size", {config.width, config.height}, 16, 8192);
  config.fps = uri.getDouble("fps", config.fps, 0.0, 1000.0);  // 0 itself is refused by validate()
  static const std::vector<std::pair<std::string, V4l2PixelFormat>> kFormats = {
      {"yuyv", V4l2PixelFormat::Yuyv},   {"mjpeg", V4l2PixelFormat::Mjpeg}, {"grey", V4l2PixelFormat::Grey},
      {"gray", V4l2PixelFormat::Grey},   {"bgr24", V4l2PixelFormat::Bgr24}, {"rgb24", V4l2PixelFormat::Rgb24}};
  std::vector<std::string> format_names;
  for (const auto& [name, format] : kFormats) format_names.push_back(name);
  const std::string format_name = uri.getChoice("format", toString(config.format), format_names);
  for (const auto& [name, format] : kFormats)
    if (name == format_name) config.format = format;
  config.buffer_count = static_cast<int>(uri.getInt("buffers", config.buffer_count, 2, 32));
  config.wait_at_start = uri.getBool("wait", config.wait_at_start);
  if (const std::string problem = config.validate(); !problem.empty())
    throw FrameSourceError("source '" + uri.text + "': " + problem);
  return config;
}

V4l2SourceConfig parseV4l2Uri(const std::string& uri, const V4l2SourceConfig& defaults) {
  return parseV4l2Uri(parseSourceUri(uri), defaults);
}

// ---------------------------------------------------------------------------------------------
// Stream: the buffers of one open device, shared with the leases of zero-copy frames.

namespace {

/// One mmap'd driver buffer; unmapped when the last owner (stream or lease) lets go.
struct MappedBuffer {
  std::shared_ptr<V4l2Device> device;
  void* address = nullptr;
  std::size_t length = 0;
  MappedBuffer(std::shared_ptr<V4l2Device> owner, void* mapped, std::size_t bytes)
      : device(std::move(owner)), address(mapped), length(bytes) {}
  ~MappedBuffer() {
    if (address != nullptr) device->unmap(address, length);
  }
  MappedBuffer(const MappedBuffer&) = delete;
  MappedBuffer& operator=(const MappedBuffer&) = delete;
};

}  // namespace

struct V4l2FrameSource::Stream {
  std::shared_ptr<V4l2Device> device;
  std::mutex mutex;                         ///< serialises ioctls of next() and of lease releases
  std::condition_variable buffer_returned;  ///< a lease gave a buffer back
  bool active = true;                       ///< false after stop(): late leases only drop their mapping
  int queued = 0;                           ///< buffers currently owned by the driver
  std::vector<std::shared_ptr<MappedBuffer>> buffers;

  /// QBUF with `mutex` held. 0 or -errno.
  int queueLocked(std::uint32_t index) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = index;
    const int result = device->ioctl(VIDIOC_QBUF, &buffer);
    if (result == 0) ++queued;
    return result;
  }
};

// ---------------------------------------------------------------------------------------------
// Source

V4l2FrameSource::V4l2FrameSource(V4l2SourceConfig config, std::unique_ptr<V4l2Device> device,
                                 V4l2Runtime runtime)
    : config_(std::move(config)), device_(std::move(device)), runtime_(std::move(runtime)) {
  if (const std::string problem = config_.validate(); !problem.empty())
    throw FrameSourceError("v4l2:" + config_.device + ": " + problem);
  if (!device_) throw FrameSourceError("v4l2:" + config_.device + ": no device given");
  if (!runtime_.monotonic_s) {
    runtime_.monotonic_s = [] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    };
  }
  if (!start(config_.wait_at_start)) {
    spdlog::warn("v4l2:{}: no such device yet; waiting for the camera (reconnecting with backoff)",
                 config_.device);
    updateStatus([&](V4l2SourceStatus& s) {
      s.connected = false;
      s.reconnecting = true;
      s.last_error = "no such device at start";
    });
  }
}

V4l2FrameSource::~V4l2FrameSource() { stop(); }

template <typename Update>
void V4l2FrameSource::updateStatus(Update&& update) {
  std::lock_guard lock(status_mutex_);
  update(status_);
}

std::string V4l2FrameSource::describe() const {
  const V4l2SourceStatus s = status();
  std::ostringstream text;
  text << "v4l2:" << config_.device;
  if (s.connected) {
    text << " (" << s.driver << ", " << s.width << "x" << s.height << " " << s.pixel_format;
    if (s.fps > 0) text << " @ " << s.fps << " fps";
    text << ")";
  } else {
    text << " (reconnecting)";
  }
  return text.str();
}

// Read every frame by the capture thread: one counter under the lock, not a copy of the whole status
// (its strings included).
std::int64_t V4l2FrameSource::skippedFrames() const {
  std::lock_guard lock(status_mutex_);
  return status_.skipped;
}

SkippedFrames V4l2FrameSource::skippedByReason() const {
  std::lock_guard lock(status_mutex_);
  SkippedFrames skipped;
  skipped[SkipReason::DeviceError] = status_.error_buffers;
  skipped[SkipReason::Truncated] = status_.short_buffers;
  skipped[SkipReason::Corrupt] = status_.decode_failures;
  return skipped;
}

FrameSourceState V4l2FrameSource::state() const {
  std::lock_guard lock(status_mutex_);
  FrameSourceState state;
  state.link = status_.reconnecting ? SourceLink::Reconnecting : SourceLink::Streaming;
  state.reconnects = status_.reconnects;
  state.reconnect_attempts = status_.reconnect_attempts;
  state.dropped = status_.dropped;
  return state;
}
std::int64_t V4l2FrameSource::droppedFrames() const {
  std::lock_guard lock(status_mutex_);
  return status_.dropped;
}

V4l2SourceStatus V4l2FrameSource::status() const {
  std::lock_guard lock(status_mutex_);
  return status_;
}

void V4l2FrameSource::interrupt() {
  {
    std::lock_guard lock(stop_mutex_);
    stop_requested_ = true;
  }
  // Wakes a backoff wait; a poll slice or a wait for a lent-out buffer notices within poll_timeout_ms.
  stop_cv_.notify_all();
}

void V4l2FrameSource::waitFor(std::chrono::milliseconds delay) {
  if (runtime_.sleep) {
    runtime_.sleep(delay);
    return;
  }
  std::unique_lock lock(stop_mutex_);
  stop_cv_.wait_for(lock, delay, [this] { return stop_requested_.load(); });
}

bool V4l2FrameSource::start(bool absent_is_ok) {
  const std::string where = "v4l2:" + config_.device;
  auto stream = std::make_shared<Stream>();
  stream->device = device_;
  auto fail = [&](const std::string& message) {
    stream->buffers.clear();  // unmap before closing
    device_->close();
    throw FrameSourceError(where + ": " + message);
  };

  if (const int opened = device_->open(config_.device); opened < 0) {
    if (absent_is_ok && (opened == -ENOENT || opened == -ENODEV || opened == -ENXIO)) return false;
    std::string hint;
    if (opened == -ENOENT) hint = "; is the camera plugged in (ls /dev/video*)?";
    if (opened == -EACCES) hint = "; add the user to the 'video' group";
    if (opened == -EBUSY) hint = "; another program may be using it";
    throw FrameSourceError(where + ": cannot open: " + errnoText(-opened) + hint);
  }

  // Capabilities of this node (device_caps), not of the whole physical device.
  v4l2_capability capability{};
  if (const int r = device_->ioctl(VIDIOC_QUERYCAP, &capability); r < 0)
    fail("not a V4L2 device (VIDIOC_QUERYCAP: " + errnoText(-r) + ")");
  const std::uint32_t caps =
      (capability.capabilities & V4L2_CAP_DEVICE_CAPS) ? capability.device_caps : capability.capabilities;
  const std::string driver = textOf(capability.driver, sizeof(capability.driver));
  const std::string card = textOf(capability.card, sizeof(capability.card));
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
    if (caps & V4L2_CAP_VIDEO_CAPTURE_MPLANE)
      fail("driver '" + driver + "' (" + card + ") only offers multi-planar capture, which is not supported");
    fail("driver '" + driver + "' (" + card + ") is not a video capture device (a metadata or output node?)");
  }
  if (!(caps & V4L2_CAP_STREAMING))
    fail("driver '" + driver + "' (" + card + ") does not support streaming I/O");

  // What the driver offers (some, e.g. v4l2loopback without a writer, offer nothing yet).
  std::vector<std::uint32_t> offered;
  for (std::uint32_t index = 0; index < 64; ++index) {
    v4l2_fmtdesc description{};
    description.index = index;
    description.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (device_->ioctl(VIDIOC_ENUM_FMT, &description) < 0) break;
    offered.push_back(description.pixelformat);
  }
  std::uint32_t wanted = toFourcc(config_.format);
  if (!offered.empty()) {
    auto isOffered = [&](std::uint32_t f) {
      return std::find(offered.begin(), offered.end(), f) != offered.end();
    };
    if (!isOffered(wanted) && config_.format == V4l2PixelFormat::Mjpeg && isOffered(V4L2_PIX_FMT_JPEG))
      wanted = V4L2_PIX_FMT_JPEG;
    if (!isOffered(wanted)) {
      std::string list;
      for (const auto f : offered) list += (list.empty() ? "" : ", ") + fourccName(f);
      fail("format " + toString(config_.format) + " is not offered by driver '" + driver + "'; it offers " +
           list + " (toposlam converts " + kConvertibleFormats + ")");
    }
  }

  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  format.fmt.pix.width = static_cast<std::uint32_t>(config_.width);
  format.fmt.pix.height = static_cast<std::uint32_t>(config_.height);
  format.fmt.pix.pixelformat = wanted;
  format.fmt.pix.field = V4L2_FIELD_ANY;
  if (const int r = device_->ioctl(VIDIOC_S_FMT, &format); r < 0)
    fail("cannot set format " + fourccName(wanted) + " " + std::to_string(config_.width) + "x" +
         std::to_string(config_.height) + " (VIDIOC_S_FMT: " + errnoText(-r) + ")" +
         (r == -EBUSY ? "; another program is streaming from it" : ""));
  // Use what the driver chose.
  const std::uint32_t fourcc = format.fmt.pix.pixelformat;
  const std::optional<CameraPixelLayout> layout = layoutOf(fourcc);
  if (!layout)
    fail("driver '" + driver + "' chose pixel format " + fourccName(fourcc) + " instead of " +
         fourccName(wanted) + ", which toposlam cannot convert (it converts " + kConvertibleFormats + ")");
  const int width = static_cast<int>(format.fmt.pix.width);
  const int height = static_cast<int>(format.fmt.pix.height);
  if (width <= 0 || height <= 0) fail("driver returned an empty image size");
  if (fourcc == V4L2_PIX_FMT_YUYV && width % 2 != 0)
    fail("driver returned an odd YUYV width " + std::to_string(width));
  std::uint32_t bytes_per_line = format.fmt.pix.bytesperline;
  const auto min_line = static_cast<std::uint32_t>(width * bytesPerPixel(*layout));
  if (*layout != CameraPixelLayout::Jpeg && bytes_per_line < min_line) bytes_per_line = min_line;
  if (fourcc != wanted)
    spdlog::warn("{}: driver chose {} instead of {}; converting from it", where, fourccName(fourcc),
                 fourccName(wanted));
  if (width != config_.width || height != config_.height)
    spdlog::info("{}: driver chose {}x{} instead of {}x{}", where, width, height, config_.width,
                 config_.height);

  // Frame rate: only if the driver supports it; failure is not fatal.
  double fps = 0.0;
  v4l2_streamparm parameters{};
  parameters.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (device_->ioctl(VIDIOC_G_PARM, &parameters) == 0 &&
      (parameters.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
    parameters.parm.capture.timeperframe.numerator = 1000;
    parameters.parm.capture.timeperframe.denominator =
        static_cast<std::uint32_t>(std::lround(config_.fps * 1000.0));
    if (device_->ioctl(VIDIOC_S_PARM, &parameters) < 0)
      spdlog::info("{}: driver refused {} fps (VIDIOC_S_PARM)", where, config_.fps);
  }
  if (device_->ioctl(VIDIOC_G_PARM, &parameters) == 0 && parameters.parm.capture.timeperframe.numerator > 0)
    fps = static_cast<double>(parameters.parm.capture.timeperframe.denominator) /
          parameters.parm.capture.timeperframe.numerator;

  v4l2_requestbuffers request{};
  request.count = static_cast<std::uint32_t>(config_.buffer_count);
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  if (const int r = device_->ioctl(VIDIOC_REQBUFS, &request); r < 0)
    fail("cannot allocate mmap buffers (VIDIOC_REQBUFS: " + errnoText(-r) + ")" +
         (r == -EBUSY ? "; another program is streaming from it" : ""));
  if (request.count == 0) fail("driver allocated no buffers");
  if (request.count < static_cast<std::uint32_t>(config_.buffer_count))
    spdlog::info(
        "{}: driver gave {} of {} buffers; a consumer holding zero-copy frames must keep fewer than that",
        where, request.count, config_.buffer_count);

  for (std::uint32_t index = 0; index < request.count; ++index) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = index;
    if (const int r = device_->ioctl(VIDIOC_QUERYBUF, &buffer); r < 0)
      fail("VIDIOC_QUERYBUF " + std::to_string(index) + ": " + errnoText(-r));
    void* address = device_->map(buffer.length, buffer.m.offset);
    if (address == nullptr) fail("cannot mmap buffer " + std::to_string(index));
    stream->buffers.push_back(std::make_shared<MappedBuffer>(device_, address, buffer.length));
  }
  {
    std::lock_guard lock(stream->mutex);
    for (std::uint32_t index = 0; index < request.count; ++index)
      if (const int r = stream->queueLocked(index); r < 0) fail("VIDIOC_QBUF: " + errnoText(-r));
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (const int r = device_->ioctl(VIDIOC_STREAMON, &type); r < 0) fail("VIDIOC_STREAMON: " + errnoText(-r));

  fourcc_ = fourcc;
  width_ = width;
  height_ = height;
  bytes_per_line_ = bytes_per_line;
  size_image_ = format.fmt.pix.sizeimage;
  have_last_driver_sequence_ = false;
  buffers_this_stream_ = 0;
  stream_ = stream;
  updateStatus([&](V4l2SourceStatus& s) {
    s.connected = true;
    s.reconnecting = false;
    s.width = width;
    s.height = height;
    s.pixel_format = fourccName(fourcc);
    s.fps = fps;
    s.driver = driver;
  });
  return true;
}

void V4l2FrameSource::stop() {
  std::shared_ptr<Stream> stream = std::move(stream_);
  if (!stream) return;
  {
    std::lock_guard lock(stream->mutex);
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    device_->ioctl(VIDIOC_STREAMOFF, &type);  // may fail on an unplugged device: nothing to do then
    stream->active = false;
    stream->queued = 0;
    stream->buffers.clear();  // leases keep their own reference to the mapping they view
    device_->close();
  }
  stream->buffer_returned.notify_all();
}

void V4l2FrameSource::lose(const std::string& reason) {
  spdlog::warn("v4l2:{}: camera lost ({}); reconnecting", config_.device, reason);
  stop();
  updateStatus([&](V4l2SourceStatus& s) {
    s.connected = false;
    s.reconnecting = true;
    s.reconnect_attempts = 0;
    s.last_error = reason;
  });
}

void V4l2FrameSource::reconnectSlice(std::chrono::milliseconds timeout) {
  int attempt = 0;
  updateStatus([&](V4l2SourceStatus& s) {
    if (backoff_left_ms_ < 0) ++s.reconnect_attempts;  // a new attempt is scheduled
    attempt = s.reconnect_attempts;
  });
  if (backoff_left_ms_ < 0) {
    std::int64_t delay_ms = config_.reconnect_initial_ms;
    for (int i = 1; i < attempt && delay_ms < config_.reconnect_max_ms; ++i) delay_ms *= 2;
    backoff_left_ms_ = std::min<std::int64_t>(delay_ms, config_.reconnect_max_ms);
  }
  // One slice of the backoff per call, so a real-time caller gets control back within its timeout.
  const std::int64_t slice_ms = std::min<std::int64_t>(backoff_left_ms_, std::max<std::int64_t>(1, timeout.count()));
  waitFor(std::chrono::milliseconds(slice_ms));
  backoff_left_ms_ -= slice_ms;
  if (stop_requested_ || backoff_left_ms_ > 0) return;
  backoff_left_ms_ = -1;
  try {
    start(false);
  } catch (const FrameSourceError& error) {
    updateStatus([&](V4l2SourceStatus& s) { s.last_error = error.what(); });
    if (config_.reconnect_max_attempts > 0 && attempt >= config_.reconnect_max_attempts)
      throw FrameSourceError("v4l2:" + config_.device + ": camera lost; gave up after " +
                             std::to_string(attempt) + " reconnect attempts; last error: " + error.what());
    return;
  }
  updateStatus([&](V4l2SourceStatus& s) {
    s.reconnect_attempts = 0;
    ++s.reconnects;
  });
  spdlog::info("v4l2:{}: camera back after {} attempt(s)", config_.device, attempt);
}

void V4l2FrameSource::requeue(std::uint32_t index) {
  std::lock_guard lock(stream_->mutex);
  if (stream_->active) stream_->queueLocked(index);  // a failure shows up at the next poll/DQBUF
}

std::optional<Frame> V4l2FrameSource::next() {
  constexpr std::chrono::milliseconds kUnbounded{std::numeric_limits<int>::max()};
  for (;;) {
    Frame frame;
    switch (nextFor(kUnbounded, frame)) {
      case SourceWait::Frame:
        return frame;
      case SourceWait::End:
        return std::nullopt;
      case SourceWait::Timeout:
        break;
    }
  }
}

SourceWait V4l2FrameSource::nextFor(std::chrono::milliseconds timeout, Frame& out) {
  if (stop_requested_) return SourceWait::End;
  const int slice_ms = static_cast<int>(std::clamp<std::int64_t>(timeout.count(), 0, config_.poll_timeout_ms));
  if (!stream_) {
    reconnectSlice(timeout);
    return stop_requested_ ? SourceWait::End : SourceWait::Timeout;
  }
  {
    // Every buffer lent out as a zero-copy frame: wait for one to come back.
    std::unique_lock lock(stream_->mutex);
    if (stream_->queued == 0) {
      stream_->buffer_returned.wait_for(lock, std::chrono::milliseconds(slice_ms),
                                        [this] { return stream_->queued > 0 || stop_requested_.load(); });
      return stop_requested_ ? SourceWait::End : SourceWait::Timeout;
    }
  }
  short revents = 0;
  const int ready = device_->poll(POLLIN, slice_ms, revents);
  if (stop_requested_) return SourceWait::End;
  if (ready == 0 || ready == -EINTR) return SourceWait::Timeout;
  if (ready < 0) {
    lose("poll: " + errnoText(-ready));
    return SourceWait::Timeout;
  }
  if (revents & (POLLERR | POLLHUP | POLLNVAL)) {
    lose(std::string("poll reported ") + ((revents & POLLHUP)   ? "POLLHUP"
                                          : (revents & POLLERR) ? "POLLERR"
                                                                : "POLLNVAL"));
    return SourceWait::Timeout;
  }
  if (!(revents & POLLIN)) return SourceWait::Timeout;

  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  int result = 0;
  {
    std::lock_guard lock(stream_->mutex);
    result = device_->ioctl(VIDIOC_DQBUF, &buffer);
    if (result == 0) --stream_->queued;
  }
  if (result == -EAGAIN || result == -EINTR) return SourceWait::Timeout;
  if (result < 0) {
    lose("VIDIOC_DQBUF: " + errnoText(-result));
    return SourceWait::Timeout;
  }
  std::optional<Frame> frame = handleBuffer(buffer);
  if (!frame) return SourceWait::Timeout;  // skipped (counted) or the device was lost
  out = std::move(*frame);
  return SourceWait::Frame;
}

std::optional<Frame> V4l2FrameSource::handleBuffer(const ::v4l2_buffer& buffer) {
  if (buffer.index >= stream_->buffers.size()) {
    lose("driver returned buffer index " + std::to_string(buffer.index) + " of " +
         std::to_string(stream_->buffers.size()));
    return std::nullopt;
  }
  // Sequence: gaps are frames the driver dropped (we were too slow, or it was).
  // The gap after the first buffer of a stream is not counted: some drivers hand out one stale buffer
  // first (v4l2loopback returns its oldest ring slot, written long before we started streaming).
  const std::uint32_t driver_sequence = buffer.sequence;
  std::int64_t gap = 0;
  ++buffers_this_stream_;
  if (have_last_driver_sequence_ && driver_sequence > last_driver_sequence_) {
    if (buffers_this_stream_ == 2) {
      first_driver_sequence_ = driver_sequence - 1;  // rebase: this buffer follows the first directly
    } else {
      gap = static_cast<std::int64_t>(driver_sequence - last_driver_sequence_) - 1;
    }
  } else {
    // First buffer of this stream, or the driver restarted its count: continue our numbering.
    first_driver_sequence_ = driver_sequence;
    stream_sequence_base_ = next_sequence_;
  }
  have_last_driver_sequence_ = true;
  last_driver_sequence_ = driver_sequence;
  const std::int64_t sequence =
      stream_sequence_base_ + static_cast<std::int64_t>(driver_sequence - first_driver_sequence_);
  next_sequence_ = sequence + 1;
  if (gap > 0) updateStatus([&](V4l2SourceStatus& s) { s.dropped += gap; });

  auto skip = [&](std::int64_t V4l2SourceStatus::*counter, const char* why) {
    requeue(buffer.index);
    std::int64_t skipped = 0;
    updateStatus([&](V4l2SourceStatus& s) {
      ++(s.*counter);
      skipped = ++s.skipped;
    });
    if (skipped == 1 || skipped % 100 == 0)
      spdlog::warn("v4l2:{}: skipped frame {} ({}); {} skipped so far", config_.device, sequence, why,
                   skipped);
    return std::optional<Frame>();
  };
  if (buffer.flags & V4L2_BUF_FLAG_ERROR)
    return skip(&V4l2SourceStatus::error_buffers, "driver flagged an error");

  const std::shared_ptr<MappedBuffer>& mapped = stream_->buffers[buffer.index];
  const auto* data = static_cast<const std::uint8_t*>(mapped->address);
  const std::size_t used = std::min<std::size_t>(buffer.bytesused, mapped->length);

  Frame frame;
  frame.sequence = sequence;
  if ((buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC &&
      (buffer.timestamp.tv_sec != 0 || buffer.timestamp.tv_usec != 0)) {
    frame.timestamp_s =
        static_cast<double>(buffer.timestamp.tv_sec) + 1e-6 * static_cast<double>(buffer.timestamp.tv_usec);
  } else {
    frame.timestamp_s = runtime_.monotonic_s();
  }

  const CameraPixelLayout layout = layoutOf(fourcc_).value_or(CameraPixelLayout::Jpeg);  // checked at start
  if (layout == CameraPixelLayout::Jpeg) {
    if (used == 0) return skip(&V4l2SourceStatus::short_buffers, "empty buffer");
    frame.image = cameraBufferToBgr(layout, data, used, width_, height_, bytes_per_line_);
    if (frame.image.empty()) return skip(&V4l2SourceStatus::decode_failures, "MJPEG did not decode");
    requeue(buffer.index);
  } else {
    const std::size_t expected =
        static_cast<std::size_t>(bytes_per_line_) * static_cast<std::size_t>(height_);
    if (used < expected || mapped->length < expected)
      return skip(&V4l2SourceStatus::short_buffers, "short buffer");
    if (layout == CameraPixelLayout::Bgr) {
      // Zero copy: the image views the driver's buffer; the lease gives it back.
      void* pixels = mapped->address;
      frame.image = cv::Mat(height_, width_, CV_8UC3, pixels, bytes_per_line_);
      std::shared_ptr<Stream> stream = stream_;
      std::shared_ptr<MappedBuffer> keep = mapped;
      const std::uint32_t index = buffer.index;
      frame.buffer_lease = std::shared_ptr<void>(pixels, [stream, keep, index](void*) {
        {
          std::lock_guard lock(stream->mutex);
          if (stream->active) stream->queueLocked(index);
        }
        stream->buffer_returned.notify_all();
      });
    } else {
      CameraImages images = cameraBufferToImages(layout, data, used, width_, height_, bytes_per_line_);
      frame.image = std::move(images.image);
      frame.grey = std::move(images.grey);
      if (frame.image.empty()) return skip(&V4l2SourceStatus::decode_failures, "conversion failed");
      requeue(buffer.index);
    }
  }
  updateStatus([](V4l2SourceStatus& s) { ++s.frames; });
  return frame;
}

}  // namespace toposlam
