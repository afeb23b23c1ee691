// LcmFragmentMonitor: the multicast socket beside liblcm's, as liblcm 1.3 opens its own (reuse the address,
// bind the port on every interface, join the group on the default one), non-blocking.
#include "lcm_fragment_monitor.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <utility>

namespace toposlam {

namespace {

/// The fragment header and the longest channel name LCM allows (63 bytes and its NUL).
constexpr std::size_t kHeadBytes = LcmFragmentTracker::kFragmentHeaderBytes + 64;
/// Datagrams read per drain: a flood is read in slices, so the caller's loop keeps its pace.
constexpr int kMaxDatagramsPerDrain = 4096;

[[noreturn]] void fail(int fd, const std::string& step, const UdpmAddress& address) {
  const int error = errno;
  if (fd >= 0) close(fd);
  throw std::runtime_error(step + " (" + address.group + ":" + std::to_string(address.port) +
                           "): " + std::strerror(error));
}

}  // namespace

LcmFragmentMonitor::LcmFragmentMonitor(const UdpmAddress& address, LcmFragmentTrackerConfig config)
    : tracker_(std::move(config)) {
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_addr.s_addr = htonl(INADDR_ANY);
  local.sin_port = htons(static_cast<std::uint16_t>(address.port));
  ip_mreq membership{};
  membership.imr_interface.s_addr = htonl(INADDR_ANY);
  if (inet_pton(AF_INET, address.group.c_str(), &membership.imr_multiaddr) != 1) {
    errno = EINVAL;
    fail(-1, "not a multicast group", address);
  }
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) fail(fd, "cannot create a UDP socket", address);
  const int one = 1;
  if (setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0)
    fail(fd, "cannot share the port", address);
  if (address.recv_buf_size > 0)  // as liblcm does with recv_buf_size; the kernel may give less
    (void)setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &address.recv_buf_size, sizeof address.recv_buf_size);
  if (bind(fd, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0)
    fail(fd, "cannot bind the port", address);
  if (setsockopt(fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &membership, sizeof membership) != 0)
    fail(fd, "cannot join the multicast group", address);
  fd_ = fd;
}

LcmFragmentMonitor::~LcmFragmentMonitor() {
  if (fd_ >= 0) close(fd_);
}

void LcmFragmentMonitor::drain(double now_s) {
  std::uint8_t head[kHeadBytes];
  for (int i = 0; i < kMaxDatagramsPerDrain; ++i) {
    sockaddr_in from{};
    socklen_t from_bytes = sizeof from;
    const ssize_t bytes = recvfrom(fd_, head, sizeof head, MSG_TRUNC | MSG_DONTWAIT,
                                   reinterpret_cast<sockaddr*>(&from), &from_bytes);
    if (bytes < 0) break;  // EAGAIN: nothing more waiting (any other error: tried again next time)
    const std::uint64_t sender =
        (std::uint64_t{ntohl(from.sin_addr.s_addr)} << 16) | std::uint64_t{ntohs(from.sin_port)};
    const auto datagram_bytes = static_cast<std::size_t>(bytes);
    tracker_.add(sender, head, std::min(datagram_bytes, sizeof head), datagram_bytes, now_s);
  }
  tracker_.expire(now_s);
}

}  // namespace toposlam
