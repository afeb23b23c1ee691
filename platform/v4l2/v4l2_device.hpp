// The seam between V4l2FrameSource and the kernel: every open/ioctl/mmap/poll/close of a V4L2 device
// goes through this small interface, so the source's error paths (EAGAIN, EINTR, ENODEV mid-stream,
// a driver that changes the format, short or error-flagged buffers, unplug and reconnect) can be
// driven by a fake device in fast unit tests, and the real system calls live in one small class.
//
// Error convention: functions return 0 (or a non-negative count) on success and -errno on failure,
// like the kernel does; they never throw and never touch the global errno of the caller.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace toposlam {

class V4l2Device {
 public:
  virtual ~V4l2Device() = default;
  /// Opens `path` non-blocking for streaming capture. 0 or -errno. At most one open device per object.
  virtual int open(const std::string& path) = 0;
  /// One VIDIOC_* request (see <linux/videodev2.h>) on the open device. 0 or -errno.
  virtual int ioctl(unsigned long request, void* arg) = 0;
  /// Maps `length` bytes of the buffer at `offset` (from VIDIOC_QUERYBUF) read/write, shared.
  /// nullptr on failure. Mappings stay valid after close() until unmapped (as with the kernel).
  virtual void* map(std::size_t length, std::int64_t offset) = 0;
  /// Undoes map(). 0 or -errno. Safe to call from any thread.
  virtual int unmap(void* address, std::size_t length) = 0;
  /// Waits up to `timeout_ms` for `events` (POLLIN, ...). Returns > 0 with `revents` set when ready,
  /// 0 on timeout, -errno on failure (-EINTR when interrupted by a signal).
  virtual int poll(short events, int timeout_ms, short& revents) = 0;
  /// Closes the device if open. Idempotent.
  virtual void close() = 0;
};

/// The real device: open(2), ioctl(2), mmap(2), poll(2) on /dev/videoN. Not thread-safe for
/// concurrent ioctls on one object; V4l2FrameSource serialises them.
std::unique_ptr<V4l2Device> makeSystemV4l2Device();

}  // namespace toposlam
