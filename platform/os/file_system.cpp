// File-system calls with their error numbers; see the header.
#include "toposlam/platform/file_system.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace toposlam {

ReadableFile::ReadableFile(const std::filesystem::path& path) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) {
    error_ = errno;
    return;
  }
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd_);
    fd_ = -1;
    status_ = Status::not_regular;
    return;
  }
  size_ = static_cast<std::uint64_t>(st.st_size);
  status_ = Status::open;
}

ReadableFile::~ReadableFile() {
  if (fd_ >= 0) ::close(fd_);
}

int ReadableFile::readFully(char* out, std::size_t size) {
  if (fd_ < 0) return EBADF;
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::read(fd_, out + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return n == 0 ? EIO : errno;  // 0: the file shrank under us
    done += static_cast<std::size_t>(n);
  }
  return 0;
}

int linkFile(const std::filesystem::path& existing, const std::filesystem::path& new_name) {
  return ::link(existing.c_str(), new_name.c_str()) == 0 ? 0 : errno;
}

int renameFile(const std::filesystem::path& from, const std::filesystem::path& to) {
  return ::rename(from.c_str(), to.c_str()) == 0 ? 0 : errno;
}

int removeFile(const std::filesystem::path& path) { return ::unlink(path.c_str()) == 0 ? 0 : errno; }

std::uint64_t fileSizeLimitBytes() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_FSIZE, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return 0;
  return static_cast<std::uint64_t>(limit.rlim_cur);
}

TemporaryFolder::TemporaryFolder(const std::string& prefix) {
  const char* base = std::getenv("TMPDIR");
  const std::filesystem::path folder = base != nullptr && *base != '\0' ? base : "/tmp";
  const std::string pattern = (folder / (prefix + "XXXXXX")).string();
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  if (::mkdtemp(name.data()) == nullptr)
    throw std::runtime_error("cannot create a temporary folder in " + folder.string() + ": " + std::strerror(errno));
  path_ = name.data();
}

TemporaryFolder::~TemporaryFolder() {
  std::error_code ignored;  // a folder someone else emptied or removed is gone all the same
  std::filesystem::remove_all(path_, ignored);
}

}  // namespace toposlam
