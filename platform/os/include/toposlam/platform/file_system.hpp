// Small file-system calls with the error number the system gave, for callers that word their own
// messages (the map file's reading, its .prev link, moving a damaged file aside): a regular file read
// whole or in pieces, a hard link that never replaces a name, a rename, a removal. Linux/POSIX.
//
// Each call returns 0 or the error number (errno; for std::strerror).
// Thread-safety: the functions are reentrant; a ReadableFile is one reader's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace toposlam {

/// A regular file open for reading; closed with the object.
class ReadableFile {
 public:
  enum class Status {
    open,         ///< ready to read
    cannot_open,  ///< open() failed: error() says why
    not_regular,  ///< it opened, but is not a regular file (a folder, a device) or could not be stat'ed
  };
  explicit ReadableFile(const std::filesystem::path& path);
  ~ReadableFile();
  ReadableFile(const ReadableFile&) = delete;
  ReadableFile& operator=(const ReadableFile&) = delete;

  Status status() const { return status_; }
  /// The error number of a failed open (Status::cannot_open), else 0.
  int error() const { return error_; }
  /// The file's size in bytes when it opened (Status::open).
  std::uint64_t size() const { return size_; }
  /// Reads exactly `size` bytes at the current offset (EINTR retried). EIO when the file ends first
  /// (it shrank under us).
  int readFully(char* out, std::size_t size);

 private:
  int fd_ = -1;
  Status status_ = Status::cannot_open;
  int error_ = 0;
  std::uint64_t size_ = 0;
};

/// A second name (hard link) for `existing`; EEXIST when `new_name` exists (it is never replaced).
int linkFile(const std::filesystem::path& existing, const std::filesystem::path& new_name);
/// Renames `from` to `to`, replacing `to` atomically when it exists.
int renameFile(const std::filesystem::path& from, const std::filesystem::path& to);
/// Removes the name `path` (not a folder).
int removeFile(const std::filesystem::path& path);

/// The largest file this process may write (RLIMIT_FSIZE, the shell's ulimit -f), bytes; 0 when unlimited.
/// A write beyond it fails with EFBIG once SIGXFSZ is ignored (signal_mask.hpp, ignoreSignals).
std::uint64_t fileSizeLimitBytes();

/// A new private folder (mode 0700) under $TMPDIR (else /tmp), named "<prefix>XXXXXX", removed with all it
/// holds when the object goes. For a command's intermediate files (`toposlam report MAP`'s run folder).
class TemporaryFolder {
 public:
  /// Throws std::runtime_error naming the folder and the reason when it cannot be created.
  explicit TemporaryFolder(const std::string& prefix);
  ~TemporaryFolder();
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace toposlam
