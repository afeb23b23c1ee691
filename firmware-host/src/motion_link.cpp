// Protocol names, link states and the counter summary (see motion_link.hpp).
#include "toposlam/firmware/motion_link.hpp"

#include <cstdio>

namespace toposlam::firmware {

std::optional<LinkProtocol> parseProtocol(const std::string& name) {
  if (name == "wheel") return LinkProtocol::Wheel;
  if (name == "mavlink") return LinkProtocol::Mavlink;
  return std::nullopt;
}

const char* protocolName(LinkProtocol protocol) { return protocol == LinkProtocol::Wheel ? "wheel" : "mavlink"; }

const char* linkStateName(LinkState state) {
  switch (state) {
    case LinkState::Waiting: return "waiting";
    case LinkState::Ok: return "ok";
    case LinkState::Silent: return "silent";
    case LinkState::Garbage: return "garbage";
  }
  return "?";
}

LinkState LinkMonitor::state(std::int64_t now_us) const {
  if (last_frame_us_ && now_us - *last_frame_us_ <= timeout_us_) return LinkState::Ok;
  const bool bytes_recent = last_byte_us_ && now_us - *last_byte_us_ <= timeout_us_;
  if (bytes_recent) {
    // Bytes, but no frame for a whole timeout (counted from the start when there never was one).
    const std::int64_t since = last_frame_us_ ? *last_frame_us_ : start_us_;
    return now_us - since > timeout_us_ ? LinkState::Garbage : (last_frame_us_ ? LinkState::Ok : LinkState::Waiting);
  }
  if (!last_byte_us_) return now_us - start_us_ > timeout_us_ ? LinkState::Silent : LinkState::Waiting;
  return LinkState::Silent;
}

std::string describeCounters(const DecoderCounters& d, const MotionCounters& m) {
  char line[512];
  std::snprintf(line, sizeof line,
                "bytes %llu (skipped %llu), frames %llu, bad crc %llu, bad length %llu, bad header %llu, "
                "unknown %llu, signed skipped %llu, mavlink1 skipped %llu, false starts %llu; motion samples %llu, "
                "restarts %llu, gaps %llu, invalid %llu, refused off the clock %llu, refused implausible %llu, "
                "clock resyncs %llu, heartbeats %llu",
                static_cast<unsigned long long>(d.bytes_in), static_cast<unsigned long long>(d.bytes_skipped),
                static_cast<unsigned long long>(d.frames), static_cast<unsigned long long>(d.bad_crc),
                static_cast<unsigned long long>(d.bad_length), static_cast<unsigned long long>(d.bad_header),
                static_cast<unsigned long long>(d.unknown_message), static_cast<unsigned long long>(d.signed_skipped),
                static_cast<unsigned long long>(d.mavlink1_skipped), static_cast<unsigned long long>(d.false_starts),
                static_cast<unsigned long long>(m.samples), static_cast<unsigned long long>(m.restarts),
                static_cast<unsigned long long>(m.gaps), static_cast<unsigned long long>(m.invalid),
                static_cast<unsigned long long>(m.off_clock), static_cast<unsigned long long>(m.implausible),
                static_cast<unsigned long long>(m.clock_resyncs), static_cast<unsigned long long>(m.heartbeats));
  return line;
}

}  // namespace toposlam::firmware
