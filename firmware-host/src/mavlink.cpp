// MAVLink 2 framing, message layouts and encoder (see mavlink.hpp). Field offsets follow the wire order
// (largest type first); the CRC_EXTRA values are those of common.xml and are re-derived from the field
// lists by a test.
#include "toposlam/firmware/mavlink.hpp"

#include <cstring>

#include "toposlam/firmware/crc16.hpp"

namespace toposlam::firmware::mavlink {

namespace {

constexpr MessageInfo kMessages[] = {
    {kHeartbeatId, 50, 9, 9, "HEARTBEAT"},
    {kAttitudeId, 39, 28, 28, "ATTITUDE"},
    {kLocalPositionNedId, 185, 28, 28, "LOCAL_POSITION_NED"},
    {kOdometryId, 91, 230, 233, "ODOMETRY"},
};

// Reads little-endian fields from a truncated payload: bytes past `size` are zero.
class PayloadReader {
 public:
  PayloadReader(const std::uint8_t* p, std::size_t size) : p_(p), size_(size) {}
  std::uint8_t u8(std::size_t at) const { return at < size_ ? p_[at] : 0; }
  std::uint32_t u32(std::size_t at) const {
    return static_cast<std::uint32_t>(u8(at)) | static_cast<std::uint32_t>(u8(at + 1)) << 8 |
           static_cast<std::uint32_t>(u8(at + 2)) << 16 | static_cast<std::uint32_t>(u8(at + 3)) << 24;
  }
  std::uint64_t u64(std::size_t at) const {
    return static_cast<std::uint64_t>(u32(at)) | static_cast<std::uint64_t>(u32(at + 4)) << 32;
  }
  float f32(std::size_t at) const {
    const std::uint32_t bits = u32(at);
    float v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }

 private:
  const std::uint8_t* p_;
  std::size_t size_;
};

void putU32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void putU64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void putF32(std::uint8_t* p, float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  putU32(p, bits);
}

std::uint16_t frameCrc(const std::uint8_t* from_len, std::size_t size, std::uint8_t crc_extra) {
  return mavlinkCrcAccumulate(mavlinkCrc(from_len, size), crc_extra);
}

bool crcMatches(const std::uint8_t* frame, std::size_t crc_at, std::uint8_t crc_extra) {
  const std::uint16_t crc = frameCrc(frame + 1, crc_at - 1, crc_extra);
  return frame[crc_at] == (crc & 0xFF) && frame[crc_at + 1] == (crc >> 8);
}

constexpr Examination need(std::size_t n) { return {Verdict::NeedMore, n, nullptr}; }
constexpr Examination reject(std::uint64_t DecoderCounters::*counter) { return {Verdict::Reject, 0, counter}; }

}  // namespace

const MessageInfo* findMessage(std::uint32_t id) {
  for (const MessageInfo& m : kMessages)
    if (m.id == id) return &m;
  return nullptr;
}

const std::uint8_t* MavlinkProtocol::findStart(const std::uint8_t* begin, const std::uint8_t* end) {
  // Both magics differ in the lowest bit only: 0xFD, 0xFE. memchr for the v2 magic is the fast path; a
  // v1 magic in between is rare on a v2 link, so a byte loop is enough.
  for (const std::uint8_t* p = begin; p < end; ++p)
    if (*p == kMagicV2 || *p == kMagicV1) return p;
  return end;
}

Examination MavlinkProtocol::examine(const std::uint8_t* b, std::size_t size) {
  if (b[0] == kMagicV2) {
    if (size < kHeaderV2) return need(kHeaderV2);
    const std::uint8_t incompat = b[2];
    if ((incompat & ~kIncompatSigned) != 0) return reject(&DecoderCounters::bad_header);
    const std::uint32_t msgid = b[7] | static_cast<std::uint32_t>(b[8]) << 8 | static_cast<std::uint32_t>(b[9]) << 16;
    const MessageInfo* info = findMessage(msgid);
    if (info == nullptr) return reject(&DecoderCounters::unknown_message);
    const std::size_t crc_at = kHeaderV2 + b[1];
    const bool is_signed = (incompat & kIncompatSigned) != 0;
    const std::size_t total = crc_at + 2 + (is_signed ? kSignatureSize : 0);
    if (size < total) return need(total);
    if (!crcMatches(b, crc_at, info->crc_extra)) return reject(&DecoderCounters::bad_crc);
    if (is_signed) return {Verdict::SkipFrame, total, &DecoderCounters::signed_skipped};
    return {Verdict::Accept, total, nullptr};
  }
  // MAVLink 1: 0xFE len seq sysid compid msgid payload crc. No truncation, so the length is exact.
  if (size < kHeaderV1) return need(kHeaderV1);
  const MessageInfo* info = findMessage(b[5]);
  if (info == nullptr) return reject(&DecoderCounters::unknown_message);
  if (b[1] != info->base_length) return reject(&DecoderCounters::bad_length);
  const std::size_t crc_at = kHeaderV1 + b[1];
  if (size < crc_at + 2) return need(crc_at + 2);
  if (!crcMatches(b, crc_at, info->crc_extra)) return reject(&DecoderCounters::bad_crc);
  return {Verdict::SkipFrame, crc_at + 2, &DecoderCounters::mavlink1_skipped};
}

Frame MavlinkProtocol::view(const std::uint8_t* b, std::size_t /*size*/) {
  Frame f{};
  f.payload_size = b[1];
  f.incompat_flags = b[2];
  f.compat_flags = b[3];
  f.seq = b[4];
  f.sysid = b[5];
  f.compid = b[6];
  f.msgid = b[7] | static_cast<std::uint32_t>(b[8]) << 8 | static_cast<std::uint32_t>(b[9]) << 16;
  f.payload = b + kHeaderV2;
  return f;
}

Message decode(const Frame& frame) {
  const PayloadReader r(frame.payload, frame.payload_size);
  switch (frame.msgid) {
    case kHeartbeatId: {
      Heartbeat m;
      m.custom_mode = r.u32(0);
      m.type = r.u8(4);
      m.autopilot = r.u8(5);
      m.base_mode = r.u8(6);
      m.system_status = r.u8(7);
      m.mavlink_version = r.u8(8);
      return m;
    }
    case kAttitudeId: {
      Attitude m;
      m.time_boot_ms = r.u32(0);
      m.roll = r.f32(4);
      m.pitch = r.f32(8);
      m.yaw = r.f32(12);
      m.rollspeed = r.f32(16);
      m.pitchspeed = r.f32(20);
      m.yawspeed = r.f32(24);
      return m;
    }
    case kLocalPositionNedId: {
      LocalPositionNed m;
      m.time_boot_ms = r.u32(0);
      m.x = r.f32(4);
      m.y = r.f32(8);
      m.z = r.f32(12);
      m.vx = r.f32(16);
      m.vy = r.f32(20);
      m.vz = r.f32(24);
      return m;
    }
    case kOdometryId: {
      Odometry m;
      m.time_usec = r.u64(0);
      m.x = r.f32(8);
      m.y = r.f32(12);
      m.z = r.f32(16);
      for (int i = 0; i < 4; ++i) m.q[i] = r.f32(20 + 4 * static_cast<std::size_t>(i));
      m.vx = r.f32(36);
      m.vy = r.f32(40);
      m.vz = r.f32(44);
      m.rollspeed = r.f32(48);
      m.pitchspeed = r.f32(52);
      m.yawspeed = r.f32(56);
      for (std::size_t i = 0; i < 21; ++i) m.pose_covariance[i] = r.f32(60 + 4 * i);
      for (std::size_t i = 0; i < 21; ++i) m.velocity_covariance[i] = r.f32(144 + 4 * i);
      m.frame_id = r.u8(228);
      m.child_frame_id = r.u8(229);
      m.reset_counter = r.u8(230);
      m.estimator_type = r.u8(231);
      m.quality = static_cast<std::int8_t>(r.u8(232));
      return m;
    }
    default:
      return std::monostate{};
  }
}

std::size_t pack(const Heartbeat& m, std::uint8_t* p) {
  putU32(p, m.custom_mode);
  p[4] = m.type;
  p[5] = m.autopilot;
  p[6] = m.base_mode;
  p[7] = m.system_status;
  p[8] = m.mavlink_version;
  return 9;
}

std::size_t pack(const Attitude& m, std::uint8_t* p) {
  putU32(p, m.time_boot_ms);
  putF32(p + 4, m.roll);
  putF32(p + 8, m.pitch);
  putF32(p + 12, m.yaw);
  putF32(p + 16, m.rollspeed);
  putF32(p + 20, m.pitchspeed);
  putF32(p + 24, m.yawspeed);
  return 28;
}

std::size_t pack(const LocalPositionNed& m, std::uint8_t* p) {
  putU32(p, m.time_boot_ms);
  putF32(p + 4, m.x);
  putF32(p + 8, m.y);
  putF32(p + 12, m.z);
  putF32(p + 16, m.vx);
  putF32(p + 20, m.vy);
  putF32(p + 24, m.vz);
  return 28;
}

std::size_t pack(const Odometry& m, std::uint8_t* p) {
  putU64(p, m.time_usec);
  putF32(p + 8, m.x);
  putF32(p + 12, m.y);
  putF32(p + 16, m.z);
  for (std::size_t i = 0; i < 4; ++i) putF32(p + 20 + 4 * i, m.q[i]);
  putF32(p + 36, m.vx);
  putF32(p + 40, m.vy);
  putF32(p + 44, m.vz);
  putF32(p + 48, m.rollspeed);
  putF32(p + 52, m.pitchspeed);
  putF32(p + 56, m.yawspeed);
  for (std::size_t i = 0; i < 21; ++i) putF32(p + 60 + 4 * i, m.pose_covariance[i]);
  for (std::size_t i = 0; i < 21; ++i) putF32(p + 144 + 4 * i, m.velocity_covariance[i]);
  p[228] = m.frame_id;
  p[229] = m.child_frame_id;
  p[230] = m.reset_counter;
  p[231] = m.estimator_type;
  p[232] = static_cast<std::uint8_t>(m.quality);
  return 233;
}

std::size_t encodeFrame(std::uint8_t* out, std::size_t capacity, const Header& h, std::uint32_t msgid,
                        std::uint8_t crc_extra, const std::uint8_t* payload, std::size_t payload_size,
                        bool signed_frame) {
  if (payload_size > 255) return 0;
  std::size_t len = payload_size;
  while (len > 1 && payload[len - 1] == 0) --len;  // MAVLink 2 truncation keeps the first byte
  const std::size_t total = kHeaderV2 + len + 2 + (signed_frame ? kSignatureSize : 0);
  if (capacity < total) return 0;
  out[0] = kMagicV2;
  out[1] = static_cast<std::uint8_t>(len);
  out[2] = signed_frame ? kIncompatSigned : 0;
  out[3] = 0;
  out[4] = h.seq;
  out[5] = h.sysid;
  out[6] = h.compid;
  out[7] = static_cast<std::uint8_t>(msgid);
  out[8] = static_cast<std::uint8_t>(msgid >> 8);
  out[9] = static_cast<std::uint8_t>(msgid >> 16);
  if (len > 0) std::memcpy(out + kHeaderV2, payload, len);
  const std::uint16_t crc = frameCrc(out + 1, kHeaderV2 - 1 + len, crc_extra);
  out[kHeaderV2 + len] = static_cast<std::uint8_t>(crc & 0xFF);
  out[kHeaderV2 + len + 1] = static_cast<std::uint8_t>(crc >> 8);
  if (signed_frame) {
    // link id, 48-bit timestamp, 48-bit signature: a placeholder (we never verify signatures).
    std::uint8_t* s = out + kHeaderV2 + len + 2;
    for (std::size_t i = 0; i < kSignatureSize; ++i) s[i] = static_cast<std::uint8_t>(0x5A ^ (i * 37));
  }
  return total;
}

std::size_t encodeFrameV1(std::uint8_t* out, std::size_t capacity, const Header& h, std::uint8_t msgid,
                          std::uint8_t crc_extra, const std::uint8_t* payload, std::size_t payload_size) {
  if (payload_size > 255) return 0;
  const std::size_t total = kHeaderV1 + payload_size + 2;
  if (capacity < total) return 0;
  out[0] = kMagicV1;
  out[1] = static_cast<std::uint8_t>(payload_size);
  out[2] = h.seq;
  out[3] = h.sysid;
  out[4] = h.compid;
  out[5] = msgid;
  if (payload_size > 0) std::memcpy(out + kHeaderV1, payload, payload_size);
  const std::uint16_t crc = frameCrc(out + 1, kHeaderV1 - 1 + payload_size, crc_extra);
  out[kHeaderV1 + payload_size] = static_cast<std::uint8_t>(crc & 0xFF);
  out[kHeaderV1 + payload_size + 1] = static_cast<std::uint8_t>(crc >> 8);
  return total;
}

namespace {
template <class M>
std::size_t encodeMessage(std::uint8_t* out, std::size_t capacity, const Header& h, std::uint32_t id, const M& m,
                          bool signed_frame) {
  std::uint8_t payload[255] = {};
  const std::size_t n = pack(m, payload);
  std::uint8_t crc_extra = 0;
  for (const MessageInfo& info : kMessages)
    if (info.id == id) crc_extra = info.crc_extra;
  return encodeFrame(out, capacity, h, id, crc_extra, payload, n, signed_frame);
}
}  // namespace

std::size_t encode(std::uint8_t* out, std::size_t capacity, const Header& h, const Heartbeat& m, bool s) {
  return encodeMessage(out, capacity, h, kHeartbeatId, m, s);
}
std::size_t encode(std::uint8_t* out, std::size_t capacity, const Header& h, const Attitude& m, bool s) {
  return encodeMessage(out, capacity, h, kAttitudeId, m, s);
}
std::size_t encode(std::uint8_t* out, std::size_t capacity, const Header& h, const LocalPositionNed& m, bool s) {
  return encodeMessage(out, capacity, h, kLocalPositionNedId, m, s);
}
std::size_t encode(std::uint8_t* out, std::size_t capacity, const Header& h, const Odometry& m, bool s) {
  return encodeMessage(out, capacity, h, kOdometryId, m, s);
}

}  // namespace toposlam::firmware::mavlink
