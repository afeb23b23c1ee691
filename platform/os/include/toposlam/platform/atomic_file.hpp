// Replacing a file atomically: the new content is written to a temporary file beside the target (same
// folder, so the same file system), fsync'ed and closed, then renamed over the target, and the folder is
// fsync'ed so that the rename itself survives a power cut. A reader sees the old file or the new one,
// never half of one; a failure at any step leaves the target as it was. Linux/POSIX (mkstemp, fsync,
// rename, open(O_DIRECTORY)).
//
// The steps are separate calls so that a caller can act between them (MapStore renames the file being
// replaced to "<path>.prev" after the flush and before the rename) and word each failure itself; each
// step returns 0 or the error number the system gave (for std::strerror). Until replaceTarget()
// succeeds, the destructor closes and removes the temporary file.
// Not thread-safe: one writer per object.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace toposlam {

/// The calls an atomic write goes through; tests override them to inject failures (a full disk, EIO).
class FileWriteOps {
 public:
  virtual ~FileWriteOps() = default;
  /// Like ::write: bytes written, or -1 with errno set.
  virtual long write(int fd, const void* data, std::size_t size) const;
  /// Like ::fsync: 0, or -1 with errno set.
  virtual int fsync(int fd) const;
  /// Like ::rename: 0, or -1 with errno set. Every rename of a save goes through here, so that a test can
  /// stop the process between two of them as a kill would.
  virtual int rename(const char* from, const char* to) const;
};

class AtomicFileWrite {
 public:
  /// Nothing is created before create(). The temporary file will be named "." + the target's file name
  /// + `infix` + six characters mkstemp picks (".map.tsm.Ab3dE9" for the infix ".").
  AtomicFileWrite(std::filesystem::path target, std::string infix);
  ~AtomicFileWrite();
  AtomicFileWrite(const AtomicFileWrite&) = delete;
  AtomicFileWrite& operator=(const AtomicFileWrite&) = delete;

  /// Creates the temporary file (mode 0644: mkstemp's 0600 is widened, best effort).
  int create();
  /// Writes all of `bytes` (a write that makes no progress counts as ENOSPC; EINTR is retried).
  int write(std::string_view bytes, const FileWriteOps& ops);
  /// fsync of the temporary file.
  int sync(const FileWriteOps& ops);
  /// Closes the temporary file (a deferred write error shows here).
  int close();
  /// Renames the temporary file over the target; from then on the temporary file is the target.
  int replaceTarget(const FileWriteOps& ops);
  /// Closes and removes the temporary file now (after a failed step; replaceTarget() not done yet).
  /// Idempotent; the destructor does it too.
  void discard();
  /// fsync of the target's folder, so that the rename is on disk. A folder that cannot be opened, or a
  /// file system that cannot sync folders (EINVAL), counts as done (0).
  int syncFolder(const FileWriteOps& ops) const;

  const std::filesystem::path& target() const { return target_; }
  /// The folder the target and the temporary file are in ("." for a bare file name).
  const std::filesystem::path& folder() const { return folder_; }
  /// The temporary file's path (empty before create()).
  const std::string& temporaryPath() const { return temporary_; }

 private:
  std::filesystem::path target_;
  std::filesystem::path folder_;
  std::string infix_;
  std::string temporary_;
  int fd_ = -1;
  bool replaced_ = false;
};

}  // namespace toposlam
