// OutputFile (output_file.hpp): a checked, atomically renamed output file.
#include "toposlam/platform/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <streambuf>
#include <vector>

namespace toposlam {

/// A write-only stream buffer over a descriptor that remembers the first write error (errno).
class OutputFile::Buffer : public std::streambuf {
 public:
  explicit Buffer(int fd) : fd_(fd), data_(64 * 1024) { setp(data_.data(), data_.data() + data_.size()); }
  ~Buffer() override {
    if (fd_ >= 0) ::close(fd_);
  }
  int fd() const { return fd_; }
  int error() const { return error_; }
  /// Writes out what is buffered; false (error() set) on failure.
  bool drain() {
    const char* p = pbase();
    std::size_t left = static_cast<std::size_t>(pptr() - pbase());
    while (left > 0 && error_ == 0) {
      const ssize_t n = ::write(fd_, p, left);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        error_ = n < 0 ? errno : EIO;
        break;
      }
      p += n;
      left -= static_cast<std::size_t>(n);
    }
    setp(data_.data(), data_.data() + data_.size());
    return error_ == 0;
  }
  /// Closes the descriptor; false (error() set) when close reports a deferred write error.
  bool close() {
    const int fd = fd_;
    fd_ = -1;
    if (fd >= 0 && ::close(fd) != 0 && error_ == 0) error_ = errno;
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
  int fd_;
  std::vector<char> data_;
  int error_ = 0;
};

OutputFile::OutputFile(std::filesystem::path target) : std::ostream(nullptr), target_(std::move(target)) {
  struct stat st {};
  const bool special = ::stat(target_.c_str(), &st) == 0 && !S_ISREG(st.st_mode);
  if (special && S_ISDIR(st.st_mode)) throw OutputFileError(target_.string() + ": cannot write: is a folder");
  int fd = -1;
  if (special) {
    fd = ::open(target_.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY);
  } else {
    const std::filesystem::path dir = target_.has_parent_path() ? target_.parent_path() : std::filesystem::path(".");
    std::string name = ".";  // built piecewise: GCC 12 warns falsely (-Wrestrict) on "." + string
    name += target_.filename().string();
    name += ".tmp-XXXXXX";
    std::string pattern = (dir / name).string();
    fd = ::mkstemp(pattern.data());
    if (fd >= 0) {
      temp_ = pattern;
      ::fchmod(fd, 0644);  // mkstemp creates 0600; outputs are for everyone to read (best effort)
    }
  }
  if (fd < 0) {
    throw OutputFileError(target_.string() + ": cannot create file: " + std::strerror(errno) +
                          " (is the folder writable?)");
  }
  buffer_ = std::make_unique<Buffer>(fd);
  rdbuf(buffer_.get());
}

OutputFile::~OutputFile() {
  rdbuf(nullptr);
  buffer_.reset();
  if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());
}

void OutputFile::commit() {
  if (committed_) return;
  flush();
  bool ok = buffer_->drain() && !fail();
  if (!ok && buffer_->error() == 0) buffer_->fail(EIO);  // a formatting failure inside the stream
  if (ok && !temp_.empty() && ::fsync(buffer_->fd()) != 0) buffer_->fail(errno);
  ok = buffer_->close() && ok && buffer_->error() == 0;
  if (!ok) {
    const std::string reason = std::strerror(buffer_->error());
    const bool replaced_nothing = !temp_.empty();
    if (replaced_nothing) ::unlink(temp_.c_str());
    temp_.clear();
    setstate(std::ios::badbit);
    throw OutputFileError(target_.string() + ": write failed: " + reason +
                          (replaced_nothing ? " (the file was not written)" : ""));
  }
  if (!temp_.empty()) {
    if (::rename(temp_.c_str(), target_.c_str()) != 0) {
      const int error = errno;
      ::unlink(temp_.c_str());
      temp_.clear();
      throw OutputFileError(target_.string() + ": cannot replace it: " + std::strerror(error));
    }
    temp_.clear();
  }
  committed_ = true;
}

void writeFileAtomically(const std::filesystem::path& target, const std::string& text) {
  OutputFile out(target);
  out << text;
  out.commit();
}

}  // namespace toposlam
