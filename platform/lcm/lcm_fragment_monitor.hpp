// A listener of our own beside liblcm on a udpm:// URL: its socket joins the same multicast group on the same
// port (SO_REUSEADDR, as liblcm's, so both receive every datagram), reads only the head of each datagram
// (MSG_TRUNC gives the full size; cheap under a flood) and feeds an LcmFragmentTracker, which counts the
// fragmented messages liblcm abandons without a word. Private to toposlam_lcm (LcmSubscriber owns one).
//
// Thread-safety: none; used by the thread that calls LcmSubscriber::handle.
#pragma once

#include <memory>
#include <string>

#include "toposlam/platform/lcm_fragment_tracker.hpp"
#include "toposlam/platform/lcm_transport.hpp"

namespace toposlam {

class LcmFragmentMonitor {
 public:
  /// Listens on `address`; throws std::runtime_error naming the step that failed (socket, bind, join).
  LcmFragmentMonitor(const UdpmAddress& address, LcmFragmentTrackerConfig config);
  ~LcmFragmentMonitor();
  LcmFragmentMonitor(const LcmFragmentMonitor&) = delete;
  LcmFragmentMonitor& operator=(const LcmFragmentMonitor&) = delete;

  /// The socket, to wait on beside liblcm's.
  int fd() const { return fd_; }
  /// Reads the datagrams waiting (up to a bound, so a flood cannot hold the caller), then expires messages
  /// with no fragment for the tracker's timeout. `now_s`: seconds of CLOCK_MONOTONIC.
  void drain(double now_s);
  const LcmFragmentStats& stats() const { return tracker_.stats(); }

 private:
  int fd_ = -1;
  LcmFragmentTracker tracker_;
};

}  // namespace toposlam
