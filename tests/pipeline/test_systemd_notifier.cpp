// SystemdNotifier against a fake NOTIFY_SOCKET: a unix datagram socket this test binds, as systemd would.
#include <catch2/catch.hpp>

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

#include "toposlam/platform/systemd_notifier.hpp"

namespace {

/// A bound unix datagram socket in /tmp; removed with the object.
class FakeNotifySocket {
 public:
  FakeNotifySocket() {
    path_ = "/tmp/toposlam-notify-" + std::to_string(getpid()) + ".sock";
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
  const std::string& path() const { return path_; }
  std::string receive() {
    char buffer[4096];
    const ssize_t n = recv(fd_, buffer, sizeof buffer, 0);
    return n > 0 ? std::string(buffer, static_cast<std::size_t>(n)) : std::string();
  }

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace

SCENARIO("toposlamd's notifications reach the socket systemd names in NOTIFY_SOCKET") {
  GIVEN("a fake NOTIFY_SOCKET and a 2 s watchdog for this process") {
    FakeNotifySocket socket;
    setenv("NOTIFY_SOCKET", socket.path().c_str(), 1);
    setenv("WATCHDOG_USEC", "2000000", 1);
    setenv("WATCHDOG_PID", std::to_string(getpid()).c_str(), 1);
    toposlam::SystemdNotifier notifier;
    WHEN("the daemon says ready, reports a status and pings the watchdog") {
      notifier.ready();
      const std::string ready = socket.receive();
      notifier.status("running: 30.0 fps");
      const std::string status = socket.receive();
      notifier.watchdog();
      const std::string watchdog = socket.receive();
      notifier.stopping();
      const std::string stopping = socket.receive();
      THEN("systemd would read READY=1, STATUS=..., WATCHDOG=1 and STOPPING=1, and the period is 2 s") {
        CHECK(notifier.active());
        CHECK(notifier.watchdogPeriodSeconds() == Approx(2.0));
        CHECK(ready == "READY=1");
        CHECK(status == "STATUS=running: 30.0 fps");
        CHECK(watchdog == "WATCHDOG=1");
        CHECK(stopping == "STOPPING=1");
      }
    }
    unsetenv("NOTIFY_SOCKET");
    unsetenv("WATCHDOG_USEC");
    unsetenv("WATCHDOG_PID");
  }
  GIVEN("no NOTIFY_SOCKET (started by hand)") {
    unsetenv("NOTIFY_SOCKET");
    toposlam::SystemdNotifier notifier;
    THEN("notifications are no-ops and there is no watchdog") {
      CHECK_FALSE(notifier.active());
      CHECK_FALSE(notifier.notify("READY=1"));
      CHECK(notifier.watchdogPeriodSeconds() == 0.0);
    }
  }
}
