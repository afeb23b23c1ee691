// The real V4L2 device behind V4l2Device: thin wrappers over open(2), ioctl(2), mmap(2), poll(2).
// Errors come back as -errno; nothing here retries (V4l2FrameSource decides what EINTR/EAGAIN mean).
#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>

#include "v4l2_device.hpp"

namespace toposlam {
namespace {

class SystemV4l2Device final : public V4l2Device {
 public:
  ~SystemV4l2Device() override { close(); }

  int open(const std::string& path) override {
    if (fd_ >= 0) return -EBUSY;
    const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return -errno;
    fd_ = fd;
    return 0;
  }

  int ioctl(unsigned long request, void* arg) override {
    if (fd_ < 0) return -EBADF;
    return ::ioctl(fd_, request, arg) < 0 ? -errno : 0;
  }

  void* map(std::size_t length, std::int64_t offset) override {
    if (fd_ < 0) return nullptr;
    void* address = ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, offset);
    return address == MAP_FAILED ? nullptr : address;
  }

  int unmap(void* address, std::size_t length) override { return ::munmap(address, length) < 0 ? -errno : 0; }

  int poll(short events, int timeout_ms, short& revents) override {
    if (fd_ < 0) return -EBADF;
    pollfd entry{fd_, events, 0};
    const int ready = ::poll(&entry, 1, timeout_ms);
    if (ready < 0) return -errno;
    revents = entry.revents;
    return ready;
  }

  void close() override {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_ = -1;
};

}  // namespace

std::unique_ptr<V4l2Device> makeSystemV4l2Device() { return std::make_unique<SystemV4l2Device>(); }

}  // namespace toposlam
