// systemd service notifications (Type=notify): READY=1 once the pipeline runs, STATUS=<text> for
// `systemctl status`, WATCHDOG=1 pings while the pipeline is healthy, STOPPING=1 at shutdown. Written as
// sd_notify(3) writes them, one datagram to the unix socket named by $NOTIFY_SOCKET (a path, or "@name" in
// the abstract namespace), but never blocking: sd_notify waits when the receiver's queue is full (ten
// datagrams unread, net.unix.max_dgram_qlen), which would freeze the daemon's main thread, and with it
// the handling of SIGTERM, for as long as PID 1 (or a test standing in for it) does not read. A
// notification that finds the queue full is dropped and counted (droppedNotifications); systemd only
// needs the latest state. Without $NOTIFY_SOCKET (run by hand) every call is a cheap no-op.
//
// Thread-safety: all members may be called from any thread (one datagram per call on a shared socket).
#pragma once

#include <sys/socket.h>
#include <sys/un.h>

#include <atomic>
#include <cstdint>
#include <string>

namespace toposlam {

class SystemdNotifier {
 public:
  SystemdNotifier();
  ~SystemdNotifier();
  SystemdNotifier(const SystemdNotifier&) = delete;
  SystemdNotifier& operator=(const SystemdNotifier&) = delete;

  /// True when $NOTIFY_SOCKET names a socket (started by systemd, or a test's fake socket).
  bool active() const { return fd_ >= 0; }
  /// The watchdog period systemd expects pings within, in seconds (WatchdogSec=), or 0 when disabled.
  double watchdogPeriodSeconds() const { return watchdog_period_s_; }
  /// Notifications not delivered because the receiver's queue was full or the socket was gone.
  std::int64_t droppedNotifications() const { return dropped_.load(); }

  void ready() const;
  void status(const std::string& text) const;
  void watchdog() const;
  void stopping() const;
  /// Any "KEY=VALUE\n..." state; returns false when it was not delivered (no socket, queue full, error).
  bool notify(const std::string& state) const;

 private:
  int fd_ = -1;
  sockaddr_un address_{};
  socklen_t address_length_ = 0;
  double watchdog_period_s_ = 0.0;
  mutable std::atomic<std::int64_t> dropped_{0};
};

}  // namespace toposlam
