// SystemdNotifier against a fake NOTIFY_SOCKET: a unix datagram socket this test binds, as systemd would.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cstdlib>
#include <string>

#include "fake_notify_socket.hpp"
#include "toposlam/platform/systemd_notifier.hpp"

using toposlam::test::FakeNotifySocket;

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
