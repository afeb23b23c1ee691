// A controller link without I/O: bytes in (from a serial port, a UDP datagram, a test), MotionSamples
// out, plus the link's health. The bridge wraps it with the device and LCM; the tests feed it directly.
//
//   MotionLink   the decoder of the configured protocol + the MotionEstimator.
//   LinkMonitor  waiting / ok / silent / garbage, from when bytes and frames last arrived.
// Plain classes: host time is passed in (microseconds, monotonic); one thread; no allocation per byte.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "toposlam/firmware/mavlink.hpp"
#include "toposlam/firmware/motion_estimator.hpp"
#include "toposlam/firmware/wheel_link.hpp"

namespace toposlam::firmware {

enum class LinkProtocol { Wheel, Mavlink };
/// "wheel" or "mavlink"; nullopt otherwise.
std::optional<LinkProtocol> parseProtocol(const std::string& name);
const char* protocolName(LinkProtocol protocol);

class MotionLink {
 public:
  explicit MotionLink(LinkProtocol protocol, MotionEstimatorConfig config = {})
      : protocol_(protocol), estimator_(config) {}

  /// Decodes `bytes` received at host time `host_us`; calls on_sample(const MotionSample&) per sample and
  /// returns the number of verified frames.
  template <class OnSample>
  std::uint64_t feed(std::span<const std::uint8_t> bytes, std::int64_t host_us, OnSample&& on_sample) {
    std::uint64_t frames = 0;
    if (protocol_ == LinkProtocol::Wheel) {
      wheel_.feed(bytes, [&](const wheel::Frame& f) {
        ++frames;
        if (auto s = estimator_.onWheel(wheel::decode(f), host_us)) on_sample(*s);
      });
    } else {
      mavlink_.feed(bytes, [&](const mavlink::Frame& f) {
        ++frames;
        if (auto s = estimator_.onMavlink(mavlink::decode(f), host_us)) on_sample(*s);
      });
    }
    return frames;
  }
  /// Drops a partial frame (the device was reopened).
  void resetFraming() {
    wheel_.reset();
    mavlink_.reset();
  }

  LinkProtocol protocol() const { return protocol_; }
  const DecoderCounters& decoder() const {
    return protocol_ == LinkProtocol::Wheel ? wheel_.counters() : mavlink_.counters();
  }
  const MotionEstimator& estimator() const { return estimator_; }

 private:
  LinkProtocol protocol_;
  wheel::Decoder wheel_;
  mavlink::Decoder mavlink_;
  MotionEstimator estimator_;
};

enum class LinkState {
  Waiting,  ///< nothing received yet
  Ok,       ///< a verified frame within the timeout
  Silent,   ///< no bytes for longer than the timeout (dead line, unplugged, controller off)
  Garbage,  ///< bytes arrive but no verified frame for longer than the timeout (wrong baud or protocol)
};
const char* linkStateName(LinkState state);

class LinkMonitor {
 public:
  LinkMonitor(std::int64_t start_us, double timeout_s)
      : start_us_(start_us), timeout_us_(static_cast<std::int64_t>(timeout_s * 1e6)) {}
  void onBytes(std::int64_t now_us) { last_byte_us_ = now_us; }
  void onFrames(std::int64_t now_us) { last_frame_us_ = now_us; }
  LinkState state(std::int64_t now_us) const;

 private:
  std::int64_t start_us_;
  std::int64_t timeout_us_;
  std::optional<std::int64_t> last_byte_us_;
  std::optional<std::int64_t> last_frame_us_;
};

/// One line of the decoder's and estimator's counters, e.g. for the bridge's periodic status.
std::string describeCounters(const DecoderCounters& d, const MotionCounters& m);

}  // namespace toposlam::firmware
