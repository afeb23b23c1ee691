// LibcameraFrameSource: one libcamera camera as a FrameSource, with zero-copy hand-off of completed
// requests from libcamera's thread to the caller of next(). See the header for the contract and
// docs/cameras.md for the design notes. Written against libcamera 0.0.3 (Debian 12); the guards on
// TOPOSLAM_LIBCAMERA_VERSION keep it compiling with newer releases whose API moved.
#include "libcamera_frame_source.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <tuple>

#include <libcamera/camera.h>
#include <libcamera/camera_manager.h>
#include <libcamera/control_ids.h>
#include <libcamera/formats.h>
#include <libcamera/framebuffer.h>
#include <libcamera/framebuffer_allocator.h>
#include <libcamera/request.h>
#include <libcamera/stream.h>
#include <libcamera/version.h>
#include <opencv2/core/mat.hpp>

#include "camera_pixels.hpp"

#define TOPOSLAM_LIBCAMERA_VERSION \
  (LIBCAMERA_VERSION_MAJOR * 10000 + LIBCAMERA_VERSION_MINOR * 100 + LIBCAMERA_VERSION_PATCH)

namespace toposlam {

namespace {

/// libcamera allows one CameraManager per process: share it while any user holds it.
std::shared_ptr<libcamera::CameraManager> sharedCameraManager() {
  static std::mutex mutex;
  static std::weak_ptr<libcamera::CameraManager> existing;
  std::lock_guard lock(mutex);
  if (auto manager = existing.lock()) return manager;
  auto manager = std::make_shared<libcamera::CameraManager>();
  if (const int r = manager->start(); r < 0)
    throw FrameSourceError("libcamera: the camera manager did not start (error " + std::to_string(r) + ")");
  existing = manager;
  return manager;
}

std::string cameraList(const libcamera::CameraManager& manager) {
  std::string list;
  for (const auto& camera : manager.cameras()) list += (list.empty() ? "" : ", ") + camera->id();
  return list.empty() ? std::string("libcamera found no cameras on this machine") : "available: " + list;
}

/// The layout (camera_pixels.hpp) of a format toposlam converts; nullopt for anything else. RGB888 is
/// B,G,R in memory (OpenCV's BGR), BGR888 is R,G,B.
std::optional<CameraPixelLayout> layoutOf(const libcamera::PixelFormat& format) {
  if (format == libcamera::formats::RGB888) return CameraPixelLayout::Bgr;
  if (format == libcamera::formats::BGR888) return CameraPixelLayout::Rgb;
  if (format == libcamera::formats::YUYV) return CameraPixelLayout::Yuyv;
  if (format == libcamera::formats::MJPEG) return CameraPixelLayout::Jpeg;
  return std::nullopt;
}

/// One mmap of a dmabuf-backed buffer (plane 0 and everything before its end).
struct Mapping {
  void* base = nullptr;
  std::size_t length = 0;
  std::uint8_t* pixels = nullptr;  // plane 0
  std::size_t pixel_bytes = 0;     // plane 0's length
};

}  // namespace

std::string LibcameraSourceConfig::validate() const {
  if (width < 16 || width > 8192) return "size: width must be in [16, 8192], got " + std::to_string(width);
  if (height < 16 || height > 8192)
    return "size: height must be in [16, 8192], got " + std::to_string(height);
  if (buffer_count < 2 || buffer_count > 16)
    return "buffers: must be in [2, 16], got " + std::to_string(buffer_count);
  if (queue_capacity < 1 || queue_capacity > 8)
    return "queue_capacity: must be in [1, 8], got " + std::to_string(queue_capacity);
  if (timeout_ms < 10 || timeout_ms > 600000)
    return "timeout_ms: must be in [10, 600000], got " + std::to_string(timeout_ms);
  return "";
}

LibcameraSourceConfig parseLibcameraUri(const SourceUri& uri) {
  if (uri.scheme != "libcamera")
    throw FrameSourceError("libcamera: URI must start with 'libcamera:', got '" + uri.text + "'");
  uri.requireOnly({"size", "buffers"});
  LibcameraSourceConfig config;
  config.camera_id = uri.path;
  std::tie(config.width, config.height) = uri.getSize("size", {config.width, config.height}, 16, 8192);
  config.buffer_count = static_cast<int>(uri.getInt("buffers", config.buffer_count, 2, 16));
  if (const std::string problem = config.validate(); !problem.empty())
    throw FrameSourceError("source '" + uri.text + "': " + problem);
  return config;
}

LibcameraSourceConfig parseLibcameraUri(const std::string& uri) { return parseLibcameraUri(parseSourceUri(uri)); }

std::vector<std::string> listLibcameraCameras() {
  auto manager = sharedCameraManager();
  std::vector<std::string> ids;
  for (const auto& camera : manager->cameras()) ids.push_back(camera->id());
  return ids;
}

std::string libcameraVersion() {
  return std::to_string(LIBCAMERA_VERSION_MAJOR) + "." + std::to_string(LIBCAMERA_VERSION_MINOR) + "." +
         std::to_string(LIBCAMERA_VERSION_PATCH);
}

// ---------------------------------------------------------------------------------------------

struct LibcameraFrameSource::Impl : std::enable_shared_from_this<Impl> {
  LibcameraSourceConfig config;
  std::shared_ptr<libcamera::CameraManager> manager;
  std::shared_ptr<libcamera::Camera> camera;
  bool acquired = false;
  std::unique_ptr<libcamera::CameraConfiguration> configuration;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator;
  libcamera::Stream* stream = nullptr;
  libcamera::PixelFormat pixel_format;
  CameraPixelLayout layout = CameraPixelLayout::Bgr;  ///< of pixel_format
  int width = 0;
  int height = 0;
  unsigned int stride = 0;
  std::vector<std::unique_ptr<libcamera::Request>> requests;
  std::map<const libcamera::FrameBuffer*, Mapping> mappings;

  std::mutex mutex;  // guards everything below
  std::condition_variable completed_cv;
  std::deque<libcamera::Request*> completed;
  bool running = false;
  bool stop_requested = false;
  std::int64_t dropped = 0;
  std::int64_t skipped = 0;
  std::int64_t failed_requests = 0;  ///< of skipped: completed with an error status or no plane
  std::int64_t delivered = 0;
  /// When the last frame (or the start) was, for the no-frame timeout; touched by next() only.
  std::chrono::steady_clock::time_point last_frame_at = std::chrono::steady_clock::now();

  /// Stops capturing; mappings stay until the last lease is gone. Idempotent.
  void stopCamera() {
    {
      std::lock_guard lock(mutex);
      if (!running) return;
      running = false;
      completed.clear();
    }
    camera->stop();  // cancels in-flight requests (their completion is ignored: running == false)
    camera->requestCompleted.disconnect(this);
  }

  ~Impl() {
    if (camera) {
      stopCamera();
      requests.clear();
      for (auto& [buffer, mapping] : mappings) munmap(mapping.base, mapping.length);
      mappings.clear();
      allocator.reset();
      if (acquired) camera->release();
      camera.reset();
    }
  }

  /// libcamera's thread.
  void onRequestCompleted(libcamera::Request* request) {
    if (request->status() == libcamera::Request::RequestCancelled) return;
    std::lock_guard lock(mutex);
    if (!running) return;
    completed.push_back(request);
    if (static_cast<int>(completed.size()) > config.queue_capacity) {
      libcamera::Request* oldest = completed.front();
      completed.pop_front();
      ++dropped;
      requeueLocked(oldest);
    }
    completed_cv.notify_one();
  }

  void requeueLocked(libcamera::Request* request) {
    if (!running) return;
    request->reuse(libcamera::Request::ReuseBuffers);
    camera->queueRequest(request);
  }

  void requeue(libcamera::Request* request) {
    std::lock_guard lock(mutex);
    requeueLocked(request);
  }
};

LibcameraFrameSource::LibcameraFrameSource(LibcameraSourceConfig config) : impl_(std::make_shared<Impl>()) {
  if (const std::string problem = config.validate(); !problem.empty())
    throw FrameSourceError("libcamera: " + problem);
  Impl& impl = *impl_;
  impl.config = config;
  impl.manager = sharedCameraManager();
  const std::string where = "libcamera:" + config.camera_id;

  if (config.camera_id.empty()) {
    const auto cameras = impl.manager->cameras();
    if (cameras.empty()) throw FrameSourceError(where + ": " + cameraList(*impl.manager));
    impl.camera = cameras.front();
  } else {
    impl.camera = impl.manager->get(config.camera_id);
    if (!impl.camera)
      throw FrameSourceError(where + ": no camera with this ID; " + cameraList(*impl.manager));
  }
  if (impl.camera->acquire() < 0) throw FrameSourceError(where + ": camera is in use by another program");
  impl.acquired = true;

  // Viewfinder role: a processed RGB/YUV stream. The roles argument is a std::vector in 0.0.x and a
  // Span in later releases; a vector converts to both.
  const std::vector<libcamera::StreamRole> roles{libcamera::StreamRole::Viewfinder};
  impl.configuration = impl.camera->generateConfiguration(roles);
  if (!impl.configuration || impl.configuration->empty())
    throw FrameSourceError(where + ": the camera offers no viewfinder stream");
  libcamera::StreamConfiguration& stream_config = impl.configuration->at(0);
  stream_config.pixelFormat = libcamera::formats::RGB888;  // B,G,R bytes in memory: OpenCV's BGR
  stream_config.size =
      libcamera::Size(static_cast<unsigned int>(config.width), static_cast<unsigned int>(config.height));
  stream_config.bufferCount = static_cast<unsigned int>(config.buffer_count);
  if (impl.configuration->validate() == libcamera::CameraConfiguration::Invalid)
    throw FrameSourceError(where + ": the camera refused every configuration close to " +
                           std::to_string(config.width) + "x" + std::to_string(config.height));
  const libcamera::PixelFormat chosen = stream_config.pixelFormat;
  if (!layoutOf(chosen))
    throw FrameSourceError(where + ": the camera only offers " + chosen.toString() +
                           ", which toposlam cannot convert (RGB888, BGR888, YUYV, MJPEG)");
  if (impl.camera->configure(impl.configuration.get()) < 0)
    throw FrameSourceError(where + ": configuring " + stream_config.toString() + " failed");
  impl.stream = stream_config.stream();
  impl.pixel_format = stream_config.pixelFormat;
  impl.layout = *layoutOf(impl.pixel_format);
  impl.width = static_cast<int>(stream_config.size.width);
  impl.height = static_cast<int>(stream_config.size.height);
  impl.stride = stream_config.stride;

  impl.allocator = std::make_unique<libcamera::FrameBufferAllocator>(impl.camera);
  if (impl.allocator->allocate(impl.stream) < 0)
    throw FrameSourceError(where + ": cannot allocate frame buffers");
  for (const auto& buffer : impl.allocator->buffers(impl.stream)) {
    const auto& planes = buffer->planes();
    if (planes.empty()) throw FrameSourceError(where + ": frame buffer without planes");
    const auto& plane = planes[0];
    const std::size_t length = static_cast<std::size_t>(plane.offset) + plane.length;
    void* base = mmap(nullptr, length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
    if (base == MAP_FAILED) throw FrameSourceError(where + ": cannot map a frame buffer");
    impl.mappings[buffer.get()] = Mapping{base, length, static_cast<std::uint8_t*>(base) + plane.offset, plane.length};
    std::unique_ptr<libcamera::Request> request = impl.camera->createRequest();
    if (!request || request->addBuffer(impl.stream, buffer.get()) < 0)
      throw FrameSourceError(where + ": cannot create a capture request");
    impl.requests.push_back(std::move(request));
  }

  impl.camera->requestCompleted.connect(impl_.get(), &Impl::onRequestCompleted);
  {
    std::lock_guard lock(impl.mutex);
    impl.running = true;
  }
  if (impl.camera->start() < 0) throw FrameSourceError(where + ": the camera did not start");
  for (auto& request : impl.requests)
    if (impl.camera->queueRequest(request.get()) < 0)
      throw FrameSourceError(where + ": cannot queue a request");
}

LibcameraFrameSource::~LibcameraFrameSource() {
  if (impl_->camera) impl_->stopCamera();  // leases may keep the mappings (and Impl) a little longer
  interrupt();
}

std::string LibcameraFrameSource::describe() const {
  std::ostringstream text;
  text << "libcamera:" << impl_->camera->id() << " (" << impl_->width << "x" << impl_->height << " "
       << impl_->pixel_format.toString() << ", libcamera " << libcameraVersion() << ")";
  return text.str();
}

std::int64_t LibcameraFrameSource::skippedFrames() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->skipped;
}

SkippedFrames LibcameraFrameSource::skippedByReason() const {
  std::lock_guard lock(impl_->mutex);
  SkippedFrames skipped;
  skipped[SkipReason::DeviceError] = impl_->failed_requests;
  skipped[SkipReason::Corrupt] = impl_->skipped - impl_->failed_requests;
  return skipped;
}

std::int64_t LibcameraFrameSource::droppedFrames() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->dropped;
}

FrameSourceState LibcameraFrameSource::state() const {
  std::lock_guard lock(impl_->mutex);
  FrameSourceState state;
  state.dropped = impl_->dropped;  // libcamera has no reconnecting: a lost camera ends with an error
  return state;
}

void LibcameraFrameSource::interrupt() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stop_requested = true;
  }
  impl_->completed_cv.notify_all();
}

std::optional<Frame> LibcameraFrameSource::next() {
  for (;;) {
    Frame frame;
    const SourceWait wait = nextFor(std::chrono::milliseconds(impl_->config.timeout_ms), frame);
    if (wait == SourceWait::Frame) return frame;
    if (wait == SourceWait::End) return std::nullopt;
  }
}

SourceWait LibcameraFrameSource::nextFor(std::chrono::milliseconds timeout, Frame& out) {
  Impl& impl = *impl_;
  {
    libcamera::Request* request = nullptr;
    {
      std::unique_lock lock(impl.mutex);
      const auto give_up_at = impl.last_frame_at + std::chrono::milliseconds(impl.config.timeout_ms);
      const auto wait_until = std::min(give_up_at, std::chrono::steady_clock::now() + timeout);
      const bool woke = impl.completed_cv.wait_until(
          lock, wait_until, [&] { return impl.stop_requested || !impl.completed.empty(); });
      if (impl.stop_requested) return SourceWait::End;
      if (!woke) {
        if (std::chrono::steady_clock::now() < give_up_at) return SourceWait::Timeout;
        throw FrameSourceError("libcamera:" + impl.camera->id() + ": no frame for " +
                               std::to_string(impl.config.timeout_ms) + " ms");
      }
      request = impl.completed.front();
      impl.completed.pop_front();
    }
    libcamera::FrameBuffer* buffer = request->findBuffer(impl.stream);
    const libcamera::FrameMetadata& metadata = buffer->metadata();
    if (metadata.status != libcamera::FrameMetadata::FrameSuccess || metadata.planes().size() == 0) {
      std::lock_guard lock(impl.mutex);
      ++impl.skipped;
      ++impl.failed_requests;
      impl.requeueLocked(request);
      return SourceWait::Timeout;  // skipped (counted)
    }
    const Mapping& mapping = impl.mappings.at(buffer);
    const std::size_t used = metadata.planes()[0].bytesused;
    Frame frame;
    frame.timestamp_s = static_cast<double>(metadata.timestamp) * 1e-9;  // ns, CLOCK_BOOTTIME/MONOTONIC
    frame.sequence = static_cast<std::int64_t>(metadata.sequence);
    if (impl.layout == CameraPixelLayout::Bgr) {
      frame.image = cv::Mat(impl.height, impl.width, CV_8UC3, mapping.pixels, impl.stride);
      std::shared_ptr<Impl> owner = impl_;
      frame.buffer_lease =
          std::shared_ptr<void>(mapping.pixels, [owner, request](void*) { owner->requeue(request); });
    } else {
      // Packed layouts: the whole mapped plane; JPEG: the bytes the camera wrote.
      const std::size_t bytes =
          impl.layout == CameraPixelLayout::Jpeg ? std::min(used, mapping.pixel_bytes) : mapping.pixel_bytes;
      CameraImages images =
          cameraBufferToImages(impl.layout, mapping.pixels, bytes, impl.width, impl.height, impl.stride);
      frame.image = std::move(images.image);
      frame.grey = std::move(images.grey);
      impl.requeue(request);
      if (frame.image.empty()) {
        std::lock_guard lock(impl.mutex);
        ++impl.skipped;
        return SourceWait::Timeout;  // skipped (counted)
      }
    }
    {
      std::lock_guard lock(impl.mutex);
      ++impl.delivered;
    }
    impl.last_frame_at = std::chrono::steady_clock::now();
    out = std::move(frame);
    return SourceWait::Frame;
  }
}

}  // namespace toposlam
