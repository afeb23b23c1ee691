// OutputFile: an output file of the offline commands written so that a reader never sees half of it and
// a write error is never silent. The text goes to a temporary file beside the target
// (".<name>.tmp-XXXXXX"); commit() flushes it, checks every write succeeded, fsyncs it, renames it over
// the target and fsyncs the folder (AtomicFileWrite, the map file's steps too). Any failure before the
// rename (a full disk, EIO, a read-only folder) throws OutputFileError naming the target and the reason,
// and the target keeps its old content. Not committed (an exception on the way):
// the temporary file is removed. A target that is not a regular file (/dev/stdout, /dev/full, a FIFO) is
// written in place, and its write errors are reported just the same.
// Not thread-safe: one writer per object.
#pragma once

#include <filesystem>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>

#include "toposlam/platform/atomic_file.hpp"

namespace toposlam {

class OutputFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class OutputFile : public std::ostream {
 public:
  /// Creates the temporary file; throws OutputFileError naming `target` when it cannot. `ops` (kept,
  /// not owned; null = the system's calls) lets tests inject write and fsync failures.
  explicit OutputFile(std::filesystem::path target, const FileWriteOps* ops = nullptr);
  ~OutputFile() override;
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  /// Flushes, checks, fsyncs and renames over the target. Throws OutputFileError; idempotent (once it
  /// has thrown, it throws the same error again).
  void commit();
  const std::filesystem::path& target() const { return target_; }

 private:
  class Buffer;
  [[noreturn]] void failCommit(const std::string& message);
  std::filesystem::path target_;
  std::string failure_;  ///< what the commit that failed said
  std::unique_ptr<AtomicFileWrite> atomic_;  ///< null when writing in place (not a regular file)
  std::unique_ptr<Buffer> buffer_;
  bool committed_ = false;
};

/// Writes `text` to `target` through an OutputFile (temporary name, checked, renamed).
void writeFileAtomically(const std::filesystem::path& target, const std::string& text);

}  // namespace toposlam
