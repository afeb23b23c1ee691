// flock-based exclusive lock; see the header.
#include "toposlam/platform/file_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <string>

namespace toposlam {

std::optional<FileLock> FileLock::tryAcquire(const std::filesystem::path& lock_file,
                                             FileLockFailure& failure) {
  std::filesystem::path locked = lock_file;
  // O_NOFOLLOW: a lock file that is a symbolic link is refused (ELOOP), never followed, so a link planted
  // beside a map cannot make us write our process id into the file it points to (issue 41).
  int fd = ::open(locked.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd < 0 && (errno == EROFS || errno == EACCES || errno == EPERM)) {
    locked = lock_file.has_parent_path() ? lock_file.parent_path() : std::filesystem::path(".");
    fd = ::open(locked.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  }
  if (fd < 0) {
    const int error = errno;
    failure = FileLockFailure{locked, true, error, 0};
    return std::nullopt;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    failure = FileLockFailure{locked, false, error, 0};
    char text[32] = {};
    if (::pread(fd, text, sizeof text - 1, 0) > 0) {
      const long pid = std::strtol(text, nullptr, 10);
      if (pid > 0) failure.holder = pid;
    }
    ::close(fd);
    return std::nullopt;
  }
  // Record our process id for the message a second process prints (best effort), only in a regular file
  // of one name: a hard link to another file is locked but never truncated.
  struct stat st {};
  if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_nlink == 1) {
    const std::string pid = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd, 0) == 0 && ::pwrite(fd, pid.data(), pid.size(), 0) < 0) {
      // ignored: the lock itself is what matters
    }
  }
  return FileLock(fd, std::move(locked));
}

FileLock::FileLock(FileLock&& other) noexcept : fd_(other.fd_), locked_(std::move(other.locked_)) {
  other.fd_ = -1;
}

FileLock& FileLock::operator=(FileLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    locked_ = std::move(other.locked_);
    other.fd_ = -1;
  }
  return *this;
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the last descriptor releases the flock
}

}  // namespace toposlam
