// Framing of the toposlam wheel link (see wheel_link.hpp, PROTOCOL.md).
#include "toposlam/firmware/wheel_link.hpp"

#include <cstring>

namespace toposlam::firmware::wheel {

const std::uint8_t* WheelLinkProtocol::findStart(const std::uint8_t* begin, const std::uint8_t* end) {
  const void* p = std::memchr(begin, TWL_SYNC1, static_cast<std::size_t>(end - begin));
  return p == nullptr ? end : static_cast<const std::uint8_t*>(p);
}

Examination WheelLinkProtocol::examine(const std::uint8_t* b, std::size_t size) {
  if (size < 2) return {Verdict::NeedMore, 2, nullptr};
  if (b[1] != TWL_SYNC2) return {Verdict::Reject, 0, &DecoderCounters::false_starts};
  if (size < TWL_HEADER_SIZE) return {Verdict::NeedMore, TWL_HEADER_SIZE, nullptr};
  if (b[2] != TWL_VERSION) return {Verdict::Reject, 0, &DecoderCounters::bad_header};
  const std::size_t length = b[4];
  if (length > TWL_MAX_PAYLOAD) return {Verdict::Reject, 0, &DecoderCounters::bad_length};
  const std::size_t total = TWL_HEADER_SIZE + length + TWL_CRC_SIZE;
  if (size < total) return {Verdict::NeedMore, total, nullptr};
  const std::uint16_t crc = twl_crc16(0xFFFF, b + 2, TWL_HEADER_SIZE - 2 + length);
  const std::uint8_t* c = b + TWL_HEADER_SIZE + length;
  if (c[0] != (crc & 0xFF) || c[1] != (crc >> 8)) return {Verdict::Reject, 0, &DecoderCounters::bad_crc};
  // Verified from here on: a frame we cannot use is dropped whole, not searched inside.
  const std::size_t known = twl_payload_size(b[3]);
  if (known == 0) return {Verdict::SkipFrame, total, &DecoderCounters::unknown_message};
  if (length < known) return {Verdict::SkipFrame, total, &DecoderCounters::bad_length};
  return {Verdict::Accept, total, nullptr};
}

Frame WheelLinkProtocol::view(const std::uint8_t* b, std::size_t /*size*/) {
  return Frame{b[2], b[3], b[5], b[4], b + TWL_HEADER_SIZE};
}

Message decode(const Frame& f) {
  switch (f.type) {
    case TWL_TYPE_HEARTBEAT: {
      twl_heartbeat_t m{};
      if (twl_unpack_heartbeat(f.payload, f.payload_size, &m)) return m;
      break;
    }
    case TWL_TYPE_WHEEL_ODOMETRY: {
      twl_wheel_odometry_t m{};
      if (twl_unpack_wheel_odometry(f.payload, f.payload_size, &m)) return m;
      break;
    }
    case TWL_TYPE_BODY_VELOCITY: {
      twl_body_velocity_t m{};
      if (twl_unpack_body_velocity(f.payload, f.payload_size, &m)) return m;
      break;
    }
    case TWL_TYPE_STATUS: {
      twl_status_t m{};
      if (twl_unpack_status(f.payload, f.payload_size, &m)) return m;
      break;
    }
    default:
      break;
  }
  return std::monostate{};
}

}  // namespace toposlam::firmware::wheel
