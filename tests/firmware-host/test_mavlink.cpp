// MAVLink 2 against the specification, checked by computations independent of the library: a bitwise
// CRC-16/MCRF4XX, the CRC_EXTRA bytes re-derived from the messages' field lists (as mavgen does), and a
// HEARTBEAT frame written out byte by byte.
#include <catch2/catch.hpp>

#include <cstring>
#include <string>
#include <vector>

#include "toposlam/firmware/crc16.hpp"
#include "toposlam/firmware/mavlink.hpp"

using namespace toposlam::firmware;

namespace {

// CRC-16/MCRF4XX the textbook way: reflected polynomial 0x8408, one bit at a time.
std::uint16_t bitwiseMcrf4xx(const std::vector<std::uint8_t>& data, std::uint16_t crc = 0xFFFF) {
  for (std::uint8_t b : data) {
    crc ^= b;
    for (int i = 0; i < 8; ++i) crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0x8408) : static_cast<std::uint16_t>(crc >> 1);
  }
  return crc;
}

struct Field {
  std::string type, name;
  int array_length = 0;
};

// CRC_EXTRA as the MAVLink generator defines it: CRC over "NAME " and, for each non-extension field in
// wire order, "type " "name " and the array length byte; then low byte xor high byte.
std::uint8_t crcExtra(const std::string& message, const std::vector<Field>& wire_order) {
  std::vector<std::uint8_t> bytes;
  auto text = [&](const std::string& s) { bytes.insert(bytes.end(), s.begin(), s.end()); };
  text(message + " ");
  for (const Field& f : wire_order) {
    text(f.type + " ");
    text(f.name + " ");
    if (f.array_length > 0) bytes.push_back(static_cast<std::uint8_t>(f.array_length));
  }
  const std::uint16_t crc = bitwiseMcrf4xx(bytes);
  return static_cast<std::uint8_t>((crc & 0xFF) ^ (crc >> 8));
}

std::vector<Field> floats(std::initializer_list<const char*> names) {
  std::vector<Field> out;
  for (const char* n : names) out.push_back({"float", n});
  return out;
}

struct Collected {
  std::vector<mavlink::Frame> frames;
  std::vector<mavlink::Message> messages;
};

Collected decodeAll(mavlink::Decoder& d, const std::vector<std::uint8_t>& bytes) {
  Collected c;
  d.feed(bytes, [&](const mavlink::Frame& f) {
    c.frames.push_back(f);
    c.messages.push_back(mavlink::decode(f));
  });
  return c;
}

}  // namespace

TEST_CASE("GIVEN the check string WHEN both MAVLink CRCs run THEN both give 0x6F91", "[firmware][mavlink]") {
  const std::vector<std::uint8_t> check{'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  CHECK(bitwiseMcrf4xx(check) == 0x6F91);
  CHECK(mavlinkCrc(check.data(), check.size()) == 0x6F91);
}

TEST_CASE("GIVEN the field lists of common.xml in wire order WHEN CRC_EXTRA is derived THEN it equals the table",
          "[firmware][mavlink]") {
  // Wire order: by type size, largest first, stable; arrays by element size; extensions excluded.
  const std::vector<Field> heartbeat{{"uint32_t", "custom_mode"}, {"uint8_t", "type"},         {"uint8_t", "autopilot"},
                                     {"uint8_t", "base_mode"},    {"uint8_t", "system_status"}, {"uint8_t", "mavlink_version"}};
  std::vector<Field> attitude{{"uint32_t", "time_boot_ms"}};
  for (const Field& f : floats({"roll", "pitch", "yaw", "rollspeed", "pitchspeed", "yawspeed"})) attitude.push_back(f);
  std::vector<Field> local{{"uint32_t", "time_boot_ms"}};
  for (const Field& f : floats({"x", "y", "z", "vx", "vy", "vz"})) local.push_back(f);
  std::vector<Field> odometry{{"uint64_t", "time_usec"}};
  for (const Field& f : floats({"x", "y", "z"})) odometry.push_back(f);
  odometry.push_back({"float", "q", 4});
  for (const Field& f : floats({"vx", "vy", "vz", "rollspeed", "pitchspeed", "yawspeed"})) odometry.push_back(f);
  odometry.push_back({"float", "pose_covariance", 21});
  odometry.push_back({"float", "velocity_covariance", 21});
  odometry.push_back({"uint8_t", "frame_id"});
  odometry.push_back({"uint8_t", "child_frame_id"});

  CHECK(crcExtra("HEARTBEAT", heartbeat) == 50);
  CHECK(crcExtra("ATTITUDE", attitude) == 39);
  CHECK(crcExtra("LOCAL_POSITION_NED", local) == 185);
  CHECK(crcExtra("ODOMETRY", odometry) == 91);
  REQUIRE(mavlink::findMessage(0) != nullptr);
  CHECK(mavlink::findMessage(0)->crc_extra == crcExtra("HEARTBEAT", heartbeat));
  CHECK(mavlink::findMessage(30)->crc_extra == crcExtra("ATTITUDE", attitude));
  CHECK(mavlink::findMessage(32)->crc_extra == crcExtra("LOCAL_POSITION_NED", local));
  CHECK(mavlink::findMessage(331)->crc_extra == crcExtra("ODOMETRY", odometry));
  CHECK(mavlink::findMessage(331)->base_length == 230);  // 8 + 4*(3+4+6+21+21) + 2
  CHECK(mavlink::findMessage(331)->full_length == 233);  // + reset_counter, estimator_type, quality
  CHECK(mavlink::findMessage(1) == nullptr);
}

TEST_CASE("GIVEN a HEARTBEAT written byte by byte from the spec WHEN decoded THEN every field is read",
          "[firmware][mavlink]") {
  // Header: magic, len 9, incompat 0, compat 0, seq 0, sysid 1, compid 1, msgid 0 (3 bytes LE).
  // Payload in wire order: custom_mode 0 (uint32), type 2 quadrotor, autopilot 12 PX4, base_mode 0x81,
  // system_status 4 active, mavlink_version 3.
  const std::vector<std::uint8_t> header{0xFD, 0x09, 0x00, 0x00, 0x00, 0x01, 0x01, 0x00, 0x00, 0x00};
  const std::vector<std::uint8_t> payload{0x00, 0x00, 0x00, 0x00, 0x02, 0x0C, 0x81, 0x04, 0x03};
  // Checksum computed here, independently: bitwise CRC over len..payload, then CRC_EXTRA 50.
  // (push_back loops: GCC 12 -O3 warns falsely about vector range inserts here.)
  std::vector<std::uint8_t> covered;
  for (std::size_t i = 1; i < header.size(); ++i) covered.push_back(header[i]);
  for (std::uint8_t b : payload) covered.push_back(b);
  covered.push_back(50);
  const std::uint16_t crc = bitwiseMcrf4xx(covered);
  CHECK(crc == 0x8C63);  // also computed offline (Python, same definition): frame ends 63 8C
  std::vector<std::uint8_t> frame;
  for (std::uint8_t b : header) frame.push_back(b);
  for (std::uint8_t b : payload) frame.push_back(b);
  frame.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  frame.push_back(static_cast<std::uint8_t>(crc >> 8));
  const std::vector<std::uint8_t> expected{0xFD, 0x09, 0x00, 0x00, 0x00, 0x01, 0x01, 0x00, 0x00, 0x00, 0x00,
                                           0x00, 0x00, 0x00, 0x02, 0x0C, 0x81, 0x04, 0x03, 0x63, 0x8C};
  REQUIRE(frame == expected);

  mavlink::Decoder d;
  const Collected c = decodeAll(d, frame);
  REQUIRE(c.frames.size() == 1);
  CHECK(c.frames[0].sysid == 1);
  CHECK(c.frames[0].compid == 1);
  CHECK(c.frames[0].msgid == 0);
  const auto* hb = std::get_if<mavlink::Heartbeat>(&c.messages[0]);
  REQUIRE(hb != nullptr);
  CHECK(hb->custom_mode == 0);
  CHECK(hb->type == 2);
  CHECK(hb->autopilot == 12);
  CHECK(hb->base_mode == 0x81);
  CHECK(hb->system_status == 4);
  CHECK(hb->mavlink_version == 3);
  CHECK(d.counters().frames == 1);
  CHECK(d.counters().bytes_skipped == 0);

  AND_THEN("the library's encoder writes the very same bytes") {
    mavlink::Heartbeat m;
    m.type = 2;
    m.autopilot = 12;
    m.base_mode = 0x81;
    m.system_status = 4;
    m.mavlink_version = 3;
    std::uint8_t out[mavlink::kMaxFrame];
    const std::size_t n = mavlink::encode(out, sizeof out, mavlink::Header{0, 1, 1}, m);
    CHECK(std::vector<std::uint8_t>(out, out + n) == expected);
  }
  AND_THEN("one flipped bit anywhere is rejected, and the counters say why") {
    for (std::size_t byte = 1; byte < frame.size(); ++byte) {
      std::vector<std::uint8_t> bad = frame;
      bad[byte] ^= 0x10;
      bad.resize(bad.size() + 300, 0);  // a damaged length may wait for more: the zeros settle it
      mavlink::Decoder d2;
      CHECK(decodeAll(d2, bad).frames.empty());
      CHECK(d2.counters().bad_crc + d2.counters().unknown_message + d2.counters().bad_header >= 1);
    }
  }
}

TEST_CASE("GIVEN an ATTITUDE with zero trailing fields WHEN encoded THEN the payload is truncated and decodes back",
          "[firmware][mavlink]") {
  mavlink::Attitude a;
  a.time_boot_ms = 1000;  // every float 0: the payload shrinks to its first nonzero-ending prefix
  std::uint8_t out[mavlink::kMaxFrame];
  const std::size_t n = mavlink::encode(out, sizeof out, mavlink::Header{7, 1, 1}, a);
  CHECK(out[1] == 2);  // 0xE8 0x03: time_boot_ms = 1000 little-endian, the zeros are cut
  CHECK(n == 10 + 2 + 2);
  CHECK(out[7] == 30);
  mavlink::Decoder d;
  const Collected c = decodeAll(d, std::vector<std::uint8_t>(out, out + n));
  REQUIRE(c.messages.size() == 1);
  const auto* back = std::get_if<mavlink::Attitude>(&c.messages[0]);
  REQUIRE(back != nullptr);
  CHECK(back->time_boot_ms == 1000);
  CHECK(back->yaw == 0.0f);

  AND_THEN("an all-zero HEARTBEAT keeps one payload byte") {
    const std::size_t m = mavlink::encode(out, sizeof out, mavlink::Header{}, mavlink::Heartbeat{0, 0, 0, 0, 0, 0});
    CHECK(out[1] == 1);
    CHECK(m == 13);
  }
}

TEST_CASE("GIVEN an ODOMETRY WHEN encoded and decoded THEN each field sits at its wire offset", "[firmware][mavlink]") {
  mavlink::Odometry o;
  o.time_usec = 0x0102030405060708ULL;
  o.x = 1.5f;
  o.y = -2.25f;
  o.z = 0.125f;
  o.q[0] = 0.5f;
  o.q[3] = -0.5f;
  o.vx = 0.75f;
  o.yawspeed = -0.3f;
  o.pose_covariance[0] = 9.0f;
  o.velocity_covariance[20] = 7.0f;
  o.frame_id = mavlink::kFrameLocalNed;
  o.child_frame_id = mavlink::kFrameBodyFrd;
  o.reset_counter = 3;
  o.estimator_type = 2;
  o.quality = -1;
  std::uint8_t payload[255] = {};
  CHECK(mavlink::pack(o, payload) == 233);
  CHECK(payload[0] == 0x08);  // time_usec first, little-endian
  float x;
  std::memcpy(&x, payload + 8, 4);
  CHECK(x == 1.5f);
  float vcov20;
  std::memcpy(&vcov20, payload + 144 + 80, 4);
  CHECK(vcov20 == 7.0f);
  CHECK(payload[228] == 1);
  CHECK(payload[229] == 12);
  CHECK(payload[232] == 0xFF);

  std::uint8_t out[mavlink::kMaxFrame];
  const std::size_t n = mavlink::encode(out, sizeof out, mavlink::Header{}, o);
  CHECK(out[7] == (331 & 0xFF));
  CHECK(out[8] == (331 >> 8));
  mavlink::Decoder d;
  const Collected c = decodeAll(d, std::vector<std::uint8_t>(out, out + n));
  REQUIRE(c.messages.size() == 1);
  const auto& b = std::get<mavlink::Odometry>(c.messages[0]);
  CHECK(b.time_usec == o.time_usec);
  CHECK(b.y == o.y);
  CHECK(b.q[3] == -0.5f);
  CHECK(b.yawspeed == o.yawspeed);
  CHECK(b.velocity_covariance[20] == 7.0f);
  CHECK(b.reset_counter == 3);
  CHECK(b.quality == -1);
}

TEST_CASE("GIVEN signed, MAVLink 1 and unknown frames WHEN decoded THEN they are skipped and counted, not delivered",
          "[firmware][mavlink]") {
  std::vector<std::uint8_t> bytes;
  std::uint8_t out[mavlink::kMaxFrame];
  mavlink::Heartbeat hb;
  hb.type = 10;
  auto add = [&](std::size_t n) { bytes.insert(bytes.end(), out, out + n); };
  add(mavlink::encode(out, sizeof out, mavlink::Header{1, 1, 1}, hb, /*signed_frame=*/true));
  std::uint8_t payload[255] = {};
  const std::size_t n = mavlink::pack(hb, payload);
  add(mavlink::encodeFrameV1(out, sizeof out, mavlink::Header{2, 1, 1}, 0, 50, payload, n));
  add(mavlink::encodeFrame(out, sizeof out, mavlink::Header{3, 1, 1}, 1, 124, payload, n));  // SYS_STATUS: unknown
  out[0] = 0xFD;
  add(mavlink::encode(out, sizeof out, mavlink::Header{4, 1, 1}, hb));  // the one to deliver
  // Unsupported incompatibility flag 0x02: not a frame we may read.
  const std::size_t m = mavlink::encode(out, sizeof out, mavlink::Header{5, 1, 1}, hb);
  out[2] = 0x02;
  add(m);

  mavlink::Decoder d;
  const Collected c = decodeAll(d, bytes);
  REQUIRE(c.frames.size() == 1);
  CHECK(c.frames[0].seq == 4);
  CHECK(d.counters().signed_skipped == 1);
  CHECK(d.counters().mavlink1_skipped == 1);
  CHECK(d.counters().unknown_message >= 1);
  CHECK(d.counters().bad_header >= 1);
  CHECK(d.counters().bytes_in == d.counters().bytes_skipped + d.counters().frame_bytes + d.buffered());
}
