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

namespace {

/// True when `path` (not followed) is the regular file of one name open as `fd`.
bool nameLeadsTo(const std::filesystem::path& path, int fd) {
  struct stat open_file {};
  struct stat named {};
  return ::fstat(fd, &open_file) == 0 && ::lstat(path.c_str(), &named) == 0 && S_ISREG(named.st_mode) &&
         named.st_nlink == 1 && named.st_dev == open_file.st_dev && named.st_ino == open_file.st_ino;
}

/// How often acquiring starts over when the lock file was removed between its open and its flock.
constexpr int kAcquireAttempts = 16;

}  // namespace

std::optional<FileLock> FileLock::tryAcquire(const std::filesystem::path& lock_file,
                                             FileLockFailure& failure) {
  for (int attempt = 1;; ++attempt) {
    std::optional<FileLock> lock = tryAcquireOnce(lock_file, failure);
    // A lock taken on a file its holder removed at release (it is no longer the name's) guards nothing.
    if (!lock || !lock->remove_at_release_ || nameLeadsTo(lock->locked_, lock->fd_) || attempt == kAcquireAttempts)
      return lock;
    lock->remove_at_release_ = false;  // not ours to remove: the name leads elsewhere now
  }
}

std::optional<FileLock> FileLock::tryAcquireOnce(const std::filesystem::path& lock_file, FileLockFailure& failure) {
  std::filesystem::path locked = lock_file;
  bool folder = false;
  // O_NOFOLLOW: a lock file that is a symbolic link is refused (ELOOP), never followed, so a link planted
  // beside a map cannot make us write our process id into the file it points to (issue 41).
  int fd = ::open(locked.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd < 0 && (errno == EROFS || errno == EACCES || errno == EPERM)) {
    locked = lock_file.has_parent_path() ? lock_file.parent_path() : std::filesystem::path(".");
    fd = ::open(locked.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    folder = true;
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
  const bool own_file = !folder && ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_nlink == 1;
  if (own_file) {
    const std::string pid = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd, 0) == 0 && ::pwrite(fd, pid.data(), pid.size(), 0) < 0) {
      // ignored: the lock itself is what matters
    }
  }
  return FileLock(fd, std::move(locked), own_file);
}

FileLock::FileLock(FileLock&& other) noexcept
    : fd_(other.fd_), locked_(std::move(other.locked_)), remove_at_release_(other.remove_at_release_) {
  other.fd_ = -1;
}

FileLock& FileLock::operator=(FileLock&& other) noexcept {
  if (this != &other) {
    release();
    fd_ = other.fd_;
    locked_ = std::move(other.locked_);
    remove_at_release_ = other.remove_at_release_;
    other.fd_ = -1;
  }
  return *this;
}

FileLock::~FileLock() { release(); }

void FileLock::release() {
  if (fd_ < 0) return;
  // Removed while still locked, and only when the name still leads to the file locked: a process that
  // opened it meanwhile finds, once it has the lock, that the name is gone and starts over (tryAcquire).
  if (remove_at_release_ && nameLeadsTo(locked_, fd_)) ::unlink(locked_.c_str());
  ::close(fd_);  // closing the last descriptor releases the flock
  fd_ = -1;
}

}  // namespace toposlam
