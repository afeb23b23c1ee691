// SystemdNotifier: sd_notify(3)'s datagram without its blocking send, and sd_watchdog_enabled(3); see the
// header.
#include "toposlam/platform/systemd_notifier.hpp"

#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <cstring>

namespace toposlam {

SystemdNotifier::SystemdNotifier() {
  std::uint64_t usec = 0;
  // unset_environment = 0: the variables stay for anyone else who asks.
  if (sd_watchdog_enabled(0, &usec) > 0) watchdog_period_s_ = static_cast<double>(usec) * 1e-6;

  const char* name = std::getenv("NOTIFY_SOCKET");
  if (name == nullptr || name[0] == '\0') return;
  const std::size_t length = std::strlen(name);
  if ((name[0] != '/' && name[0] != '@') || length >= sizeof address_.sun_path) {
    spdlog::warn("systemd: NOTIFY_SOCKET '{}' is neither a socket path nor an abstract '@name' that fits a unix "
                 "address; no service notifications",
                 name);
    return;
  }
  address_.sun_family = AF_UNIX;
  std::memcpy(address_.sun_path, name, length);
  if (name[0] == '@') address_.sun_path[0] = '\0';  // the abstract namespace: no terminating zero counts
  address_length_ = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + length + (name[0] == '/' ? 1 : 0));
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd_ < 0) spdlog::warn("systemd: no socket for service notifications: {}", std::strerror(errno));
}

SystemdNotifier::~SystemdNotifier() {
  if (fd_ >= 0) ::close(fd_);
}

bool SystemdNotifier::notify(const std::string& state) const {
  if (fd_ < 0) return false;
  const ssize_t sent = ::sendto(fd_, state.data(), state.size(), MSG_NOSIGNAL,
                                reinterpret_cast<const sockaddr*>(&address_), address_length_);
  if (sent == static_cast<ssize_t>(state.size())) return true;
  const int error = sent < 0 ? errno : EMSGSIZE;
  // Said once, then counted: a receiver that stopped reading would otherwise fill the log.
  if (dropped_.fetch_add(1) == 0)
    spdlog::warn("systemd: a notification was not delivered ({}); later ones that fail are only counted",
                 error == EAGAIN ? "the notify socket's queue is full: systemd is not reading it"
                                 : std::strerror(error));
  return false;
}

void SystemdNotifier::ready() const { notify("READY=1"); }
void SystemdNotifier::status(const std::string& text) const { notify("STATUS=" + text); }
void SystemdNotifier::watchdog() const { notify("WATCHDOG=1"); }
void SystemdNotifier::stopping() const { notify("STOPPING=1"); }

}  // namespace toposlam
