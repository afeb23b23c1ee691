// A stand-in for systemd's notify socket: a unix datagram socket bound in /tmp, named to the process
// under test in NOTIFY_SOCKET. Used by the notifier's unit test and by daemon end-to-end tests.
#pragma once

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <stdexcept>
#include <string>

namespace toposlam::test {

class FakeNotifySocket {
 public:
  /// `tag` makes the path unique among sockets of one process.
  explicit FakeNotifySocket(const std::string& tag = "notify") {
    path_ = "/tmp/toposlam-" + tag + "-" + std::to_string(getpid()) + ".sock";
    unlink(path_.c_str());
    fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    path_.copy(address.sun_path, sizeof(address.sun_path) - 1);
    if (fd_ < 0 || bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0)
      throw std::runtime_error("cannot bind the fake notify socket " + path_);
    timeval timeout{5, 0};  // a receive never hangs the test
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  }
  ~FakeNotifySocket() {
    close(fd_);
    unlink(path_.c_str());
  }
  FakeNotifySocket(const FakeNotifySocket&) = delete;
  FakeNotifySocket& operator=(const FakeNotifySocket&) = delete;
  const std::string& path() const { return path_; }
  /// The next datagram, or "" after 5 s without one.
  std::string receive() {
    char buffer[4096];
    const ssize_t n = recv(fd_, buffer, sizeof buffer, 0);
    return n > 0 ? std::string(buffer, static_cast<std::size_t>(n)) : std::string();
  }

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace toposlam::test
