// systemd service notifications (Type=notify): READY=1 once the pipeline runs, STATUS=<text> for
// `systemctl status`, WATCHDOG=1 pings while the pipeline is healthy, STOPPING=1 at shutdown. Through
// libsystemd's sd_notify, which writes to the unix datagram socket named by $NOTIFY_SOCKET; without it
// (run by hand) every call is a cheap no-op.
//
// Thread-safety: all members may be called from any thread (sd_notify is reentrant).
#pragma once

#include <string>

namespace toposlam {

class SystemdNotifier {
 public:
  SystemdNotifier();
  /// True when $NOTIFY_SOCKET is set (started by systemd, or a test's fake socket).
  bool active() const { return active_; }
  /// The watchdog period systemd expects pings within, in seconds (WatchdogSec=), or 0 when disabled.
  double watchdogPeriodSeconds() const { return watchdog_period_s_; }

  void ready() const;
  void status(const std::string& text) const;
  void watchdog() const;
  void stopping() const;
  /// Any "KEY=VALUE\n..." state; returns false when it could not be sent (no socket, error).
  bool notify(const std::string& state) const;

 private:
  bool active_ = false;
  double watchdog_period_s_ = 0.0;
};

}  // namespace toposlam
