// A scripted V4L2 device for unit tests: a tiny model of a capture driver (formats, S_FMT, mmap
// buffers, a driver-owned queue) driven by a script of events (frames, errors, unplugs), so the error
// paths of V4l2FrameSource run in microseconds without a kernel. Single-threaded use only.
#pragma once

#include <linux/videodev2.h>
#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <deque>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "v4l2_device.hpp"

namespace toposlam::test {

struct FakeV4l2Event {
  enum class Kind { Frame, PollError, PollHangup, PollTimeout, DqbufError, Unplug };
  Kind kind = Kind::Frame;
  std::vector<std::uint8_t> payload;  ///< Frame: bytes written into the buffer
  std::int64_t bytesused = -1;        ///< Frame: reported bytesused (-1: payload size)
  std::uint32_t sequence = 0;         ///< Frame: driver sequence number
  std::uint32_t flags = 0;            ///< Frame: extra buffer flags (e.g. V4L2_BUF_FLAG_ERROR)
  double timestamp_s = 0.0;           ///< Frame: monotonic timestamp
  int error = 0;                      ///< PollError / DqbufError: the errno
};

/// Shared state observed by tests after the device object moved into the source.
struct FakeV4l2State {
  // Driver model.
  std::string driver = "fake";
  std::uint32_t device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  std::vector<std::uint32_t> offered = {V4L2_PIX_FMT_YUYV};
  /// S_FMT result: if set, the driver forces this format/size regardless of the request.
  std::uint32_t forced_format = 0;
  std::uint32_t forced_width = 0;
  std::uint32_t forced_height = 0;
  std::uint32_t buffer_count = 4;
  std::uint32_t buffer_length = 0;  ///< 0: sizeimage
  bool monotonic_timestamps = true;

  // Script.
  std::deque<FakeV4l2Event> events;
  std::deque<int> open_errors;    ///< errno for the next open() calls (consumed one per call)
  std::function<void()> on_idle;  ///< called when the script is exhausted (e.g. interrupt)

  // Observations.
  int opens = 0;
  int closes = 0;
  int qbufs = 0;
  int streamons = 0;
  int mapped = 0;  ///< currently mapped buffers
  std::uint32_t width = 0, height = 0, pixelformat = 0, bytesperline = 0, sizeimage = 0;
  std::map<std::uint32_t, std::vector<std::uint8_t>> buffers;  // index -> memory
  std::deque<std::uint32_t> queued;                            // driver-owned buffer indices
  bool is_open = false;
  bool streaming = false;
};

class FakeV4l2Device final : public V4l2Device {
 public:
  explicit FakeV4l2Device(FakeV4l2State& state) : s_(state) {}

  int open(const std::string&) override {
    if (!s_.open_errors.empty()) {
      const int error = s_.open_errors.front();
      s_.open_errors.pop_front();
      return -error;
    }
    ++s_.opens;
    s_.is_open = true;
    return 0;
  }

  void close() override {
    if (!s_.is_open) return;
    ++s_.closes;
    s_.is_open = false;
    s_.streaming = false;
    s_.queued.clear();
  }

  void* map(std::size_t length, std::int64_t offset) override {
    auto found = s_.buffers.find(static_cast<std::uint32_t>(offset));
    if (!s_.is_open || found == s_.buffers.end() || found->second.size() < length) return nullptr;
    ++s_.mapped;
    return found->second.data();
  }

  int unmap(void*, std::size_t) override {
    --s_.mapped;
    return 0;
  }

  int poll(short, int, short& revents) override {
    revents = 0;
    if (!s_.is_open) return -EBADF;
    if (s_.events.empty()) {
      if (s_.on_idle) s_.on_idle();
      return 0;
    }
    FakeV4l2Event& event = s_.events.front();
    switch (event.kind) {
      case FakeV4l2Event::Kind::PollError: {
        const int error = event.error;
        s_.events.pop_front();
        return -error;
      }
      case FakeV4l2Event::Kind::PollTimeout:
        s_.events.pop_front();
        return 0;
      case FakeV4l2Event::Kind::PollHangup:
        s_.events.pop_front();
        revents = POLLHUP | POLLERR;
        return 1;
      case FakeV4l2Event::Kind::Unplug:
        // The node vanishes: this poll reports an error and the next opens fail until replugged.
        s_.events.pop_front();
        revents = POLLERR;
        return 1;
      default:
        revents = POLLIN;
        return 1;
    }
  }

  int ioctl(unsigned long request, void* arg) override {
    if (!s_.is_open) return -EBADF;
    switch (request) {
      case VIDIOC_QUERYCAP: {
        auto* cap = static_cast<v4l2_capability*>(arg);
        std::memset(cap, 0, sizeof(*cap));
        std::memcpy(cap->driver, s_.driver.c_str(), std::min<std::size_t>(s_.driver.size(), 15));
        std::memcpy(cap->card, "Fake camera", 11);
        cap->device_caps = s_.device_caps;
        cap->capabilities = s_.device_caps | V4L2_CAP_DEVICE_CAPS;
        return 0;
      }
      case VIDIOC_ENUM_FMT: {
        auto* description = static_cast<v4l2_fmtdesc*>(arg);
        if (description->index >= s_.offered.size()) return -EINVAL;
        description->pixelformat = s_.offered[description->index];
        return 0;
      }
      case VIDIOC_S_FMT: {
        auto& pix = static_cast<v4l2_format*>(arg)->fmt.pix;
        if (s_.forced_format != 0) pix.pixelformat = s_.forced_format;
        if (s_.forced_width != 0) pix.width = s_.forced_width;
        if (s_.forced_height != 0) pix.height = s_.forced_height;
        const std::uint32_t bpp = pix.pixelformat == V4L2_PIX_FMT_YUYV    ? 2
                                  : pix.pixelformat == V4L2_PIX_FMT_GREY  ? 1
                                  : pix.pixelformat == V4L2_PIX_FMT_MJPEG ? 0
                                                                          : 3;
        pix.bytesperline = pix.width * bpp;
        pix.sizeimage = bpp == 0 ? pix.width * pix.height * 2 : pix.bytesperline * pix.height;
        s_.width = pix.width;
        s_.height = pix.height;
        s_.pixelformat = pix.pixelformat;
        s_.bytesperline = pix.bytesperline;
        s_.sizeimage = pix.sizeimage;
        return 0;
      }
      case VIDIOC_G_PARM: {
        auto* parameters = static_cast<v4l2_streamparm*>(arg);
        parameters->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
        parameters->parm.capture.timeperframe = {1, 30};
        return 0;
      }
      case VIDIOC_S_PARM:
        return 0;
      case VIDIOC_REQBUFS: {
        auto* request_buffers = static_cast<v4l2_requestbuffers*>(arg);
        request_buffers->count = std::min(request_buffers->count, s_.buffer_count);
        const std::uint32_t length = s_.buffer_length != 0 ? s_.buffer_length : s_.sizeimage;
        // Old buffers may still be mapped by leases: keep their memory alive (a moved vector keeps it).
        for (auto& entry : s_.buffers) retired_.push_back(std::move(entry.second));
        s_.buffers.clear();
        for (std::uint32_t i = 0; i < request_buffers->count; ++i) s_.buffers[i].assign(length, 0);
        return 0;
      }
      case VIDIOC_QUERYBUF: {
        auto* buffer = static_cast<v4l2_buffer*>(arg);
        auto found = s_.buffers.find(buffer->index);
        if (found == s_.buffers.end()) return -EINVAL;
        buffer->length = static_cast<std::uint32_t>(found->second.size());
        buffer->m.offset = buffer->index;
        return 0;
      }
      case VIDIOC_QBUF: {
        auto* buffer = static_cast<v4l2_buffer*>(arg);
        if (s_.buffers.find(buffer->index) == s_.buffers.end()) return -EINVAL;
        for (auto q : s_.queued)
          if (q == buffer->index) return -EINVAL;  // already queued: a bug in the source
        s_.queued.push_back(buffer->index);
        ++s_.qbufs;
        return 0;
      }
      case VIDIOC_STREAMON:
        ++s_.streamons;
        s_.streaming = true;
        return 0;
      case VIDIOC_STREAMOFF:
        s_.streaming = false;
        s_.queued.clear();
        return 0;
      case VIDIOC_DQBUF:
        return dequeue(*static_cast<v4l2_buffer*>(arg));
      default:
        return -ENOTTY;
    }
  }

 private:
  int dequeue(v4l2_buffer& buffer) {
    if (s_.events.empty()) return -EAGAIN;
    FakeV4l2Event event = s_.events.front();
    if (event.kind == FakeV4l2Event::Kind::DqbufError) {
      s_.events.pop_front();
      return -event.error;
    }
    if (event.kind != FakeV4l2Event::Kind::Frame) return -EAGAIN;
    if (s_.queued.empty()) return -EAGAIN;
    s_.events.pop_front();
    const std::uint32_t index = s_.queued.front();
    s_.queued.pop_front();
    std::vector<std::uint8_t>& memory = s_.buffers[index];
    std::copy_n(event.payload.begin(), std::min(event.payload.size(), memory.size()), memory.begin());
    buffer.index = index;
    buffer.bytesused = static_cast<std::uint32_t>(
        event.bytesused >= 0 ? event.bytesused : static_cast<std::int64_t>(event.payload.size()));
    buffer.sequence = event.sequence;
    buffer.flags = event.flags | (s_.monotonic_timestamps ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC : 0U);
    const auto whole = static_cast<long>(event.timestamp_s);
    buffer.timestamp.tv_sec = whole;
    buffer.timestamp.tv_usec =
        static_cast<long>((event.timestamp_s - static_cast<double>(whole)) * 1e6 + 0.5);
    return 0;
  }

  FakeV4l2State& s_;
  std::vector<std::vector<std::uint8_t>> retired_;
};

}  // namespace toposlam::test
