// Test helper: LCM fragment datagrams of a message, sent to a udpm:// URL's group from one socket (one
// sender, as liblcm sees it), so a test can leave fragments out and watch what the receiver counts.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "toposlam/platform/lcm_fragment_tracker.hpp"
#include "toposlam/platform/lcm_transport.hpp"

namespace toposlam::test {

/// `message` on `channel` as `count` fragment datagrams (LCM's 'LC03' layout: fragment 0 carries the
/// channel).
inline std::vector<std::vector<std::uint8_t>> lcmFragments(const std::string& channel,
                                                           const std::vector<std::uint8_t>& message,
                                                           std::uint32_t seqno, std::uint16_t count) {
  auto put = [](std::vector<std::uint8_t>& out, std::uint32_t value, int bytes) {
    for (int shift = 8 * (bytes - 1); shift >= 0; shift -= 8)
      out.push_back(static_cast<std::uint8_t>(value >> shift));
  };
  const std::size_t chunk = (message.size() + count - 1) / count;
  std::vector<std::vector<std::uint8_t>> datagrams;
  for (std::uint16_t number = 0; number < count; ++number) {
    const std::size_t offset = std::min(message.size(), chunk * number);
    const std::size_t end = std::min(message.size(), offset + chunk);
    std::vector<std::uint8_t> d;
    put(d, LcmFragmentTracker::kFragmentMagic, 4);
    put(d, seqno, 4);
    put(d, static_cast<std::uint32_t>(message.size()), 4);
    put(d, static_cast<std::uint32_t>(offset), 4);
    put(d, number, 2);
    put(d, count, 2);
    if (number == 0) d.insert(d.end(), channel.c_str(), channel.c_str() + channel.size() + 1);
    d.insert(d.end(), message.begin() + static_cast<std::ptrdiff_t>(offset),
             message.begin() + static_cast<std::ptrdiff_t>(end));
    datagrams.push_back(std::move(d));
  }
  return datagrams;
}

/// One UDP socket sending to a udpm:// URL's group and port, on this host only (TTL 0, looped back).
class MulticastSender {
 public:
  explicit MulticastSender(const std::string& url) {
    const auto address = parseUdpmUrl(url);
    if (!address) throw std::invalid_argument("not a udpm:// URL: " + url);
    to_.sin_family = AF_INET;
    to_.sin_port = htons(static_cast<std::uint16_t>(address->port));
    inet_pton(AF_INET, address->group.c_str(), &to_.sin_addr);
    fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw std::runtime_error("cannot create a UDP socket");
    const unsigned char ttl = 0, loop = 1;
    setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
    setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop);
  }
  ~MulticastSender() { close(fd_); }
  MulticastSender(const MulticastSender&) = delete;
  MulticastSender& operator=(const MulticastSender&) = delete;
  /// True when the datagram was sent.
  bool send(const std::vector<std::uint8_t>& datagram) const {
    return sendto(fd_, datagram.data(), datagram.size(), 0, reinterpret_cast<const sockaddr*>(&to_),
                  sizeof to_) == static_cast<ssize_t>(datagram.size());
  }

 private:
  int fd_ = -1;
  sockaddr_in to_{};
};

}  // namespace toposlam::test
