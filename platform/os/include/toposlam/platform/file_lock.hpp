// An exclusive advisory lock on a file (flock(LOCK_EX | LOCK_NB)), held while the FileLock lives: a second
// process asking for it is refused at once (no waiting). The holder writes its process id into the file,
// so that a refused process can say who holds it. When the lock file cannot be created because its
// folder is read-only or not ours, the folder itself is locked instead (a second process is still
// refused). The lock goes with the last descriptor: the object closes it, and first removes the lock file
// when it is still the one it locked (same device and inode, a regular file of one name), so that a clean
// exit leaves no stale "*.lock" behind; a file someone put in its place, a hard link or the folder locked
// instead is never removed. Because a lock file may vanish, acquiring checks after flock() that the name
// still leads to the file locked (else someone released and removed it meanwhile) and tries again.
// Linux (flock).
//
// Thread-safety: acquire from any thread; one owner per object. flock locks are per open file, so a
// second FileLock on the same file in the same process is refused too.
#pragma once

#include <filesystem>
#include <optional>

namespace toposlam {

/// Why FileLock::tryAcquire failed.
struct FileLockFailure {
  std::filesystem::path path;  ///< the file (or folder) it tried to lock
  bool cannot_open = false;    ///< true: it could not be opened or created; false: flock refused it
  int error = 0;               ///< the error number; EWOULDBLOCK: another process holds the lock
  long holder = 0;             ///< that process' id when the file records it, else 0
};

class FileLock {
 public:
  /// Locks `lock_file` (created with mode 0644 when missing) or, when that fails with EROFS, EACCES or
  /// EPERM, the folder it would be in. Empty when refused or failed; `failure` says why.
  static std::optional<FileLock> tryAcquire(const std::filesystem::path& lock_file, FileLockFailure& failure);
  FileLock(FileLock&& other) noexcept;
  FileLock& operator=(FileLock&& other) noexcept;
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;
  ~FileLock();
  /// The file (or folder) locked.
  const std::filesystem::path& lockedPath() const { return locked_; }

 private:
  FileLock(int fd, std::filesystem::path locked, bool remove_at_release)
      : fd_(fd), locked_(std::move(locked)), remove_at_release_(remove_at_release) {}
  static std::optional<FileLock> tryAcquireOnce(const std::filesystem::path& lock_file, FileLockFailure& failure);
  void release();
  int fd_ = -1;
  std::filesystem::path locked_;
  bool remove_at_release_ = false;  ///< a lock file of ours (not the folder, not a hard link)
};

}  // namespace toposlam
