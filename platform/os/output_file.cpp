// OutputFile (output_file.hpp): a checked, atomically renamed output file.
#include "toposlam/platform/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <streambuf>
#include <string_view>
#include <utility>
#include <vector>

namespace toposlam {

/// A write-only stream buffer that remembers the first write error (errno). It writes through the
/// AtomicFileWrite of a regular file, or straight to the descriptor of a special file written in place.
class OutputFile::Buffer : public std::streambuf {
 public:
  Buffer(AtomicFileWrite* atomic, int fd, const FileWriteOps& ops)
      : atomic_(atomic), fd_(fd), ops_(ops), data_(64 * 1024) {
    setp(data_.data(), data_.data() + data_.size());
  }
  ~Buffer() override {
    if (fd_ >= 0) ::close(fd_);
  }
  int error() const { return error_; }
  const FileWriteOps& ops() const { return ops_; }
  /// Writes out what is buffered; false (error() set) on failure.
  bool drain() {
    const std::string_view pending(pbase(), static_cast<std::size_t>(pptr() - pbase()));
    if (!pending.empty() && error_ == 0) fail(atomic_ != nullptr ? atomic_->write(pending, ops_) : writeInPlace(pending));
    setp(data_.data(), data_.data() + data_.size());
    return error_ == 0;
  }
  /// Closes what was written (a deferred write error shows here): false (error() set) on failure.
  bool close() {
    if (atomic_ != nullptr) {
      if (error_ == 0) fail(atomic_->sync(ops_));
      fail(atomic_->close());
    } else if (const int fd = std::exchange(fd_, -1); fd >= 0 && ::close(fd) != 0) {
      fail(errno);
    }
    return error_ == 0;
  }
  void fail(int error) {
    if (error_ == 0) error_ = error;
  }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  int writeInPlace(std::string_view bytes) const {
    while (!bytes.empty()) {
      const long n = ops_.write(fd_, bytes.data(), bytes.size());
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return n < 0 ? errno : EIO;
      bytes.remove_prefix(static_cast<std::size_t>(n));
    }
    return 0;
  }

  AtomicFileWrite* atomic_;  ///< null: writing in place to fd_
  int fd_;
  const FileWriteOps& ops_;
  std::vector<char> data_;
  int error_ = 0;
};

namespace {
const FileWriteOps kSystemOps;
}  // namespace

OutputFile::OutputFile(std::filesystem::path target, const FileWriteOps* ops)
    : std::ostream(nullptr), target_(std::move(target)) {
  const FileWriteOps& calls = ops != nullptr ? *ops : kSystemOps;
  struct stat st {};
  const bool special = ::stat(target_.c_str(), &st) == 0 && !S_ISREG(st.st_mode);
  if (special && S_ISDIR(st.st_mode)) throw OutputFileError(target_.string() + ": cannot write: is a folder");
  int fd = -1;
  int error = 0;
  if (special) {
    fd = ::open(target_.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) error = errno;
  } else {
    atomic_ = std::make_unique<AtomicFileWrite>(target_, ".tmp-");
    error = atomic_->create();  // mode 0644: outputs are for everyone to read
  }
  if (error != 0) {
    throw OutputFileError(target_.string() + ": cannot create file: " + std::strerror(error) +
                          " (is the folder writable?)");
  }
  buffer_ = std::make_unique<Buffer>(atomic_.get(), fd, calls);
  rdbuf(buffer_.get());
}

OutputFile::~OutputFile() {
  rdbuf(nullptr);
  buffer_.reset();
  atomic_.reset();  // not committed: closes and removes the temporary file
}

void OutputFile::failCommit(const std::string& message) {
  // The AtomicFileWrite stays (the buffer points at it); its temporary file goes now, so a caller that
  // catches the error sees the folder as it was. A later commit() throws the same message again.
  if (atomic_ != nullptr) atomic_->discard();
  failure_ = message;
  setstate(std::ios::badbit);
  throw OutputFileError(failure_);
}

void OutputFile::commit() {
  if (committed_) return;
  if (!failure_.empty()) throw OutputFileError(failure_);
  flush();
  bool ok = buffer_->drain() && !fail();
  if (!ok && buffer_->error() == 0) buffer_->fail(EIO);  // a formatting failure inside the stream
  ok = buffer_->close() && ok;
  if (!ok)
    failCommit(target_.string() + ": write failed: " + std::strerror(buffer_->error()) +
               (atomic_ != nullptr ? " (the file was not written)" : ""));
  if (atomic_ != nullptr) {
    if (const int error = atomic_->replaceTarget(buffer_->ops()); error != 0)
      failCommit(target_.string() + ": cannot replace it: " + std::strerror(error));
    if (const int error = atomic_->syncFolder(buffer_->ops()); error != 0)
      failCommit(target_.string() + ": written, but its folder could not be flushed (the new file may not survive a "
                 "power cut): " + std::strerror(error));
  }
  committed_ = true;
}

void writeFileAtomically(const std::filesystem::path& target, const std::string& text) {
  OutputFile out(target);
  out << text;
  out.commit();
}

}  // namespace toposlam
