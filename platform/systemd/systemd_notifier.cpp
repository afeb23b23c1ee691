// SystemdNotifier: sd_notify(3) and sd_watchdog_enabled(3); see the header.
#include "toposlam/platform/systemd_notifier.hpp"

#include <systemd/sd-daemon.h>

#include <cstdint>
#include <cstdlib>

namespace toposlam {

SystemdNotifier::SystemdNotifier() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  active_ = socket != nullptr && socket[0] != '\0';
  std::uint64_t usec = 0;
  // unset_environment = 0: the variables stay for anyone else who asks.
  if (sd_watchdog_enabled(0, &usec) > 0) watchdog_period_s_ = static_cast<double>(usec) * 1e-6;
}

bool SystemdNotifier::notify(const std::string& state) const {
  if (!active_) return false;
  return sd_notify(0, state.c_str()) > 0;
}

void SystemdNotifier::ready() const { notify("READY=1"); }
void SystemdNotifier::status(const std::string& text) const { notify("STATUS=" + text); }
void SystemdNotifier::watchdog() const { notify("WATCHDOG=1"); }
void SystemdNotifier::stopping() const { notify("STOPPING=1"); }

}  // namespace toposlam
