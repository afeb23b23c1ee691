// SystemdNotifier against a fake NOTIFY_SOCKET: a unix datagram socket this test binds, as systemd would.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <future>
#include <string>
#include <thread>

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
  GIVEN("a NOTIFY_SOCKET nobody reads (PID 1 busy, or a test that stopped listening)") {
    FakeNotifySocket socket("unread");
    setenv("NOTIFY_SOCKET", socket.path().c_str(), 1);
    toposlam::SystemdNotifier notifier;
    WHEN("the daemon pings the watchdog 100 times, ten times the receiver's queue") {
      // Off this thread: a notifier that blocks (sd_notify does) must fail the test, not hang it.
      auto pings = std::async(std::launch::async, [&] {
        int delivered = 0;
        for (int i = 0; i < 100; ++i) delivered += notifier.notify("WATCHDOG=1") ? 1 : 0;
        return delivered;
      });
      const bool returned = pings.wait_for(std::chrono::seconds(10)) == std::future_status::ready;
      if (!returned) {
        FAIL_CHECK("100 notifications to an unread socket did not return within 10 s: the send blocks");
        std::quick_exit(1);  // the blocked thread cannot be joined
      }
      const int delivered = pings.get();
      THEN("every call returns; the queue takes what it holds and the rest are dropped and counted") {
        CHECK(delivered >= 1);
        CHECK(delivered < 100);
        CHECK(notifier.droppedNotifications() + delivered == 100);
      }
      AND_WHEN("the receiver reads again") {
        std::string first;
        for (int i = 0; i < delivered; ++i) first = socket.receive();
        THEN("the next notification is delivered") {
          CHECK(first == "WATCHDOG=1");
          CHECK(notifier.notify("STOPPING=1"));
          CHECK(socket.receive() == "STOPPING=1");
        }
      }
    }
    unsetenv("NOTIFY_SOCKET");
  }
  GIVEN("NOTIFY_SOCKET naming a socket in the abstract namespace (@name), as systemd may") {
    const std::string name = "@toposlam-test-notify-" + std::to_string(getpid());
    setenv("NOTIFY_SOCKET", name.c_str(), 1);
    toposlam::SystemdNotifier notifier;
    THEN("the notifier is active and a send with nobody bound there fails without blocking") {
      CHECK(notifier.active());
      CHECK_FALSE(notifier.notify("READY=1"));
      CHECK(notifier.droppedNotifications() == 1);
    }
    unsetenv("NOTIFY_SOCKET");
  }
  GIVEN("NOTIFY_SOCKET that is neither a path nor @name") {
    setenv("NOTIFY_SOCKET", "relative/notify.sock", 1);
    toposlam::SystemdNotifier notifier;
    THEN("there are no notifications") {
      CHECK_FALSE(notifier.active());
      CHECK_FALSE(notifier.notify("READY=1"));
    }
    unsetenv("NOTIFY_SOCKET");
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
