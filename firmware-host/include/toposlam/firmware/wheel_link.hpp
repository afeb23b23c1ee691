// The toposlam wheel link on the host: framing rules for FrameDecoder and typed messages. The byte layout
// has one home, the controller's C encoder (encoder/toposlam_wheel_link.h); this file only frames and
// dispatches. Protocol description: firmware-host/PROTOCOL.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <variant>

#include "toposlam/firmware/frame_decoder.hpp"
#include "toposlam_wheel_link.h"

namespace toposlam::firmware::wheel {

/// A verified frame; `payload` points into the decoder buffer.
struct Frame {
  std::uint8_t version;
  std::uint8_t type;
  std::uint8_t seq;
  std::uint8_t payload_size;
  const std::uint8_t* payload;
};

struct WheelLinkProtocol {
  static constexpr std::size_t kMaxFrame = TWL_MAX_FRAME;
  using Frame = wheel::Frame;
  static const std::uint8_t* findStart(const std::uint8_t* begin, const std::uint8_t* end);
  static Examination examine(const std::uint8_t* buffer, std::size_t size);
  static Frame view(const std::uint8_t* frame, std::size_t size);
};
using Decoder = FrameDecoder<WheelLinkProtocol>;

using Message = std::variant<std::monostate, twl_heartbeat_t, twl_wheel_odometry_t, twl_body_velocity_t, twl_status_t>;
/// The typed message of a verified frame (the decoder only accepts known types of sufficient length).
Message decode(const Frame& frame);

}  // namespace toposlam::firmware::wheel
