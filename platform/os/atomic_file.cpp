// Atomic file replacement; see the header.
#include "toposlam/platform/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <vector>

namespace toposlam {

long FileWriteOps::write(int fd, const void* data, std::size_t size) const { return ::write(fd, data, size); }
int FileWriteOps::fsync(int fd) const { return ::fsync(fd); }
int FileWriteOps::rename(const char* from, const char* to) const { return ::rename(from, to); }

AtomicFileWrite::AtomicFileWrite(std::filesystem::path target, std::string infix)
    : target_(std::move(target)),
      folder_(target_.has_parent_path() ? target_.parent_path() : std::filesystem::path(".")),
      infix_(std::move(infix)) {}

AtomicFileWrite::~AtomicFileWrite() { discard(); }

void AtomicFileWrite::discard() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!replaced_ && !temporary_.empty()) ::unlink(temporary_.c_str());
  if (!replaced_) temporary_.clear();
}

int AtomicFileWrite::create() {
  std::string name = ".";  // built piecewise: GCC 12 warns falsely (-Wrestrict) on "." + string
  name += target_.filename().string();
  name += infix_;
  name += "XXXXXX";
  const std::string pattern = (folder_ / name).string();
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  fd_ = ::mkostemp(buffer.data(), O_CLOEXEC);  // O_EXCL too: never an existing file, nor a link
  if (fd_ < 0) return errno;
  temporary_ = buffer.data();
  ::fchmod(fd_, 0644);  // mkstemp creates 0600; what we write is not secret (best effort)
  return 0;
}

int AtomicFileWrite::write(std::string_view bytes, const FileWriteOps& ops) {
  std::size_t written = 0;
  while (written < bytes.size()) {
    const long n = ops.write(fd_, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return n < 0 ? errno : ENOSPC;
    written += static_cast<std::size_t>(n);
  }
  return 0;
}

int AtomicFileWrite::sync(const FileWriteOps& ops) { return ops.fsync(fd_) != 0 ? errno : 0; }

int AtomicFileWrite::close() {
  const int fd = fd_;
  fd_ = -1;
  if (fd < 0) return 0;  // closed already
  return ::close(fd) != 0 ? errno : 0;
}

int AtomicFileWrite::replaceTarget(const FileWriteOps& ops) {
  if (ops.rename(temporary_.c_str(), target_.c_str()) != 0) return errno;
  replaced_ = true;
  return 0;
}

int AtomicFileWrite::syncFolder(const FileWriteOps& ops) const {
  const int folder_fd = ::open(folder_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (folder_fd < 0) return 0;
  const int result = ops.fsync(folder_fd);
  const int error = errno;
  ::close(folder_fd);
  return result != 0 && error != EINVAL ? error : 0;
}

}  // namespace toposlam
