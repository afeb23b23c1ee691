// MAVLink 2 on the host: framing for FrameDecoder, the four messages toposlam reads, and an encoder for
// the emulator and the tests. From the public protocol specification (mavlink.io, common.xml):
//
//   0xFD len incompat compat seq sysid compid msgid[3, LE] payload[len] crc[2, LE] (signature[13])
//   crc = CRC-16/MCRF4XX over len..payload, then the message's CRC_EXTRA byte.
//   Payload fields are ordered by type size, largest first (extensions appended in declared order);
//   trailing zero bytes are truncated by the sender (at least one byte is kept), so the receiver
//   zero-extends.
//
// Frames of other message ids cannot be verified (their CRC_EXTRA is unknown here): they are rejected
// and the search resumes inside them (counted as unknown_message). Signed frames (incompat flag 0x01)
// and MAVLink 1 frames (0xFE) of known ids are verified and skipped whole; we do not check signatures,
// so we never act on them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <variant>

#include "toposlam/firmware/frame_decoder.hpp"

namespace toposlam::firmware::mavlink {

inline constexpr std::uint8_t kMagicV2 = 0xFD;
inline constexpr std::uint8_t kMagicV1 = 0xFE;
inline constexpr std::size_t kHeaderV2 = 10;
inline constexpr std::size_t kHeaderV1 = 6;
inline constexpr std::size_t kSignatureSize = 13;
inline constexpr std::uint8_t kIncompatSigned = 0x01;
inline constexpr std::size_t kMaxFrame = kHeaderV2 + 255 + 2 + kSignatureSize;  // 280

inline constexpr std::uint32_t kHeartbeatId = 0;
inline constexpr std::uint32_t kAttitudeId = 30;
inline constexpr std::uint32_t kLocalPositionNedId = 32;
inline constexpr std::uint32_t kOdometryId = 331;

/// What the decoder knows about a message id.
struct MessageInfo {
  std::uint32_t id;
  std::uint8_t crc_extra;
  std::uint8_t base_length;  ///< payload bytes without extensions (MAVLink 1 frames have exactly this)
  std::uint8_t full_length;  ///< with the extensions we know
  const char* name;
};
/// nullptr for ids we do not know.
const MessageInfo* findMessage(std::uint32_t id);

/// A verified MAVLink 2 frame; `payload` points into the decoder buffer (zero-extend past payload_size).
struct Frame {
  std::uint8_t payload_size;
  std::uint8_t incompat_flags;
  std::uint8_t compat_flags;
  std::uint8_t seq;
  std::uint8_t sysid;
  std::uint8_t compid;
  std::uint32_t msgid;
  const std::uint8_t* payload;
};

/// Framing rules for FrameDecoder<MavlinkProtocol>.
struct MavlinkProtocol {
  static constexpr std::size_t kMaxFrame = mavlink::kMaxFrame;
  using Frame = mavlink::Frame;
  static const std::uint8_t* findStart(const std::uint8_t* begin, const std::uint8_t* end);
  static Examination examine(const std::uint8_t* buffer, std::size_t size);
  static Frame view(const std::uint8_t* frame, std::size_t size);
};
using Decoder = FrameDecoder<MavlinkProtocol>;

// --- messages (units as in common.xml) ------------------------------------------------------------------

struct Heartbeat {
  std::uint32_t custom_mode = 0;
  std::uint8_t type = 0;       ///< MAV_TYPE
  std::uint8_t autopilot = 0;  ///< MAV_AUTOPILOT
  std::uint8_t base_mode = 0;  ///< MAV_MODE_FLAG bits
  std::uint8_t system_status = 0;
  std::uint8_t mavlink_version = 3;
};

struct Attitude {
  std::uint32_t time_boot_ms = 0;
  float roll = 0, pitch = 0, yaw = 0;                  ///< rad (yaw: clockwise from north, NED)
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;   ///< rad/s
};

struct LocalPositionNed {
  std::uint32_t time_boot_ms = 0;
  float x = 0, y = 0, z = 0;     ///< m, north east down
  float vx = 0, vy = 0, vz = 0;  ///< m/s, north east down
};

/// MAV_FRAME values used by ODOMETRY.
inline constexpr std::uint8_t kFrameLocalNed = 1;
inline constexpr std::uint8_t kFrameBodyFrd = 12;
inline constexpr std::uint8_t kFrameLocalFrd = 20;

struct Odometry {
  std::uint64_t time_usec = 0;
  float x = 0, y = 0, z = 0;  ///< m, in frame_id
  float q[4] = {1, 0, 0, 0};  ///< w x y z, rotation from frame_id to the body
  float vx = 0, vy = 0, vz = 0;                       ///< m/s, in child_frame_id
  float rollspeed = 0, pitchspeed = 0, yawspeed = 0;  ///< rad/s, body
  float pose_covariance[21] = {};
  float velocity_covariance[21] = {};
  std::uint8_t frame_id = kFrameLocalNed;
  std::uint8_t child_frame_id = kFrameBodyFrd;
  std::uint8_t reset_counter = 0;   ///< extension
  std::uint8_t estimator_type = 0;  ///< extension
  std::int8_t quality = 0;          ///< extension, percent, -1 = failed
};

using Message = std::variant<std::monostate, Heartbeat, Attitude, LocalPositionNed, Odometry>;
/// The typed message of a verified frame (monostate for a known id we do not decode).
Message decode(const Frame& frame);

// --- encoder (host side: emulator, tests) ---------------------------------------------------------------

struct Header {
  std::uint8_t seq = 0;
  std::uint8_t sysid = 1;
  std::uint8_t compid = 1;
};

/// Full-length payloads (before truncation); return the payload size.
std::size_t pack(const Heartbeat& m, std::uint8_t* payload);
std::size_t pack(const Attitude& m, std::uint8_t* payload);
std::size_t pack(const LocalPositionNed& m, std::uint8_t* payload);
std::size_t pack(const Odometry& m, std::uint8_t* payload);

/// Frames a payload as MAVLink 2 (trailing zeros truncated, one byte kept). With `signed_frame` the
/// incompat flag is set and 13 signature bytes (link id, timestamp, a fake signature) follow. Returns
/// the frame size, 0 if `capacity` is too small.
std::size_t encodeFrame(std::uint8_t* out, std::size_t capacity, const Header& header, std::uint32_t msgid,
                        std::uint8_t crc_extra, const std::uint8_t* payload, std::size_t payload_size,
                        bool signed_frame = false);
/// Frames a payload as MAVLink 1 (no truncation; msgid < 256).
std::size_t encodeFrameV1(std::uint8_t* out, std::size_t capacity, const Header& header, std::uint8_t msgid,
                          std::uint8_t crc_extra, const std::uint8_t* payload, std::size_t payload_size);

/// One message as a MAVLink 2 frame (see encodeFrame).
std::size_t encode(std::uint8_t* out, std::size_t capacity, const Header& header, const Heartbeat& m,
                   bool signed_frame = false);
std::size_t encode(std::uint8_t* out, std::size_t capacity, const Header& header, const Attitude& m,
                   bool signed_frame = false);
std::size_t encode(std::uint8_t* out, std::size_t capacity, const Header& header, const LocalPositionNed& m,
                   bool signed_frame = false);
std::size_t encode(std::uint8_t* out, std::size_t capacity, const Header& header, const Odometry& m,
                   bool signed_frame = false);

}  // namespace toposlam::firmware::mavlink
