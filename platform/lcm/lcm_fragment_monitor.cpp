// LcmFragmentMonitor: the multicast socket beside liblcm's, as liblcm 1.3 opens its own (reuse the address,
// bind the port on every interface, join the group on the default one), non-blocking.
#include "lcm_fragment_monitor.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/uio.h>
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
/// Datagrams read per system call.
constexpr int kBatch = 64;

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
  // inet_aton, as liblcm reads the group: it takes the forms inet_pton refuses ("4026420291", "239.1").
  if (inet_aton(address.group.c_str(), &membership.imr_multiaddr) == 0) {
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
  // recvmmsg: one system call per batch, not per datagram (a flood is tens of thousands a second).
  std::uint8_t heads[kBatch][kHeadBytes];
  sockaddr_in senders[kBatch];
  iovec vectors[kBatch];
  mmsghdr messages[kBatch];
  for (int read = 0; read < kMaxDatagramsPerDrain;) {
    for (int i = 0; i < kBatch; ++i) {
      vectors[i] = iovec{heads[i], kHeadBytes};
      messages[i] = mmsghdr{};
      messages[i].msg_hdr.msg_name = &senders[i];
      messages[i].msg_hdr.msg_namelen = sizeof senders[i];
      messages[i].msg_hdr.msg_iov = &vectors[i];
      messages[i].msg_hdr.msg_iovlen = 1;
    }
    // MSG_TRUNC: msg_len is each datagram's full size, though only its head is copied.
    const int got = recvmmsg(fd_, messages, kBatch, MSG_TRUNC | MSG_DONTWAIT, nullptr);
    if (got <= 0) break;  // EAGAIN: nothing more waiting (any other error: tried again next time)
    for (int i = 0; i < got; ++i) {
      const std::uint64_t sender = (std::uint64_t{ntohl(senders[i].sin_addr.s_addr)} << 16) |
                                   std::uint64_t{ntohs(senders[i].sin_port)};
      const std::size_t datagram_bytes = messages[i].msg_len;
      tracker_.add(sender, heads[i], std::min(datagram_bytes, kHeadBytes), datagram_bytes, now_s);
    }
    read += got;
    if (got < kBatch) break;
  }
  tracker_.expire(now_s);
}

}  // namespace toposlam
