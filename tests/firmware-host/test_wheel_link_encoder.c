/*
 * Host test of the controller-side C99 encoder (firmware-host/encoder), built with -std=c99 -Wall -Wextra
 * -pedantic like a firmware would build it. Expected frames were computed independently (a Python
 * struct.pack + bitwise CRC-16/CCITT-FALSE, see PROTOCOL.md's example section). Returns 0 when all pass.
 */
#include <stdio.h>
#include <string.h>

#include "toposlam_wheel_link.h"

static int g_failures = 0;

#define CHECK(cond)                                                  \
  do {                                                               \
    if (!(cond)) {                                                   \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
      ++g_failures;                                                  \
    }                                                                \
  } while (0)

static void test_crc_check_value(void) {
  const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  CHECK(twl_crc16(0xFFFFu, check, sizeof check) == 0x29B1u);
  /* Continuation over two pieces equals one pass. */
  CHECK(twl_crc16(twl_crc16(0xFFFFu, check, 4), check + 4, 5) == 0x29B1u);
}

static void test_heartbeat_bytes(void) {
  static const uint8_t expected[] = {0xA5, 0x5A, 0x01, 0x01, 0x10, 0x07, 0x40, 0x42, 0x0F, 0x00, 0x00, 0x00,
                                     0x00, 0x00, 0xEF, 0xBE, 0x01, 0x02, 0x03, 0x00, 0x00, 0x00, 0x28, 0x1E};
  twl_heartbeat_t m;
  uint8_t out[TWL_MAX_FRAME];
  size_t n;
  m.time_us = 1000000u;
  m.boot_id = 0xBEEFu;
  m.fw_major = 1;
  m.fw_minor = 2;
  m.rx_errors = 3;
  n = twl_encode_heartbeat(out, sizeof out, 7, &m);
  CHECK(n == sizeof expected);
  CHECK(memcmp(out, expected, sizeof expected) == 0);
}

static void test_wheel_odometry_bytes_and_round_trip(void) {
  static const uint8_t expected[] = {0xA5, 0x5A, 0x01, 0x02, 0x14, 0xC8, 0xA0, 0x25, 0x26, 0x00,
                                     0x00, 0x00, 0x00, 0x00, 0x79, 0x29, 0xED, 0xFF, 0xB1, 0xCB,
                                     0x74, 0x00, 0x2C, 0x01, 0x01, 0x00, 0xA9, 0x4C};
  twl_wheel_odometry_t m, back;
  uint8_t out[TWL_MAX_FRAME];
  size_t n;
  m.time_us = 2500000u;
  m.left_um = -1234567;
  m.right_um = 7654321;
  m.track_mm = 300;
  m.flags = TWL_ODOM_DRIVING;
  m.reserved = 0;
  n = twl_encode_wheel_odometry(out, sizeof out, 200, &m);
  CHECK(n == sizeof expected);
  CHECK(memcmp(out, expected, sizeof expected) == 0);
  CHECK(twl_unpack_wheel_odometry(out + TWL_HEADER_SIZE, out[4], &back) == 1);
  CHECK(back.time_us == m.time_us && back.left_um == m.left_um && back.right_um == m.right_um);
  CHECK(back.track_mm == 300 && back.flags == TWL_ODOM_DRIVING);
  /* The trailing two bytes are the CRC of version..payload, low byte first. */
  CHECK(twl_crc16(0xFFFFu, out + 2, n - 4) == (uint16_t)(out[n - 2] | (out[n - 1] << 8)));
}

static void test_extreme_values_round_trip(void) {
  twl_body_velocity_t v, vb;
  twl_status_t s, sb;
  uint8_t out[TWL_MAX_FRAME];
  v.time_us = 0xFFFFFFFFFFFFFFFFu;
  v.vx_mm_s = -2147483647 - 1;
  v.vy_mm_s = 2147483647;
  v.wz_mrad_s = -1;
  CHECK(twl_encode_body_velocity(out, sizeof out, 0, &v) == TWL_HEADER_SIZE + TWL_BODY_VELOCITY_SIZE + 2);
  CHECK(twl_unpack_body_velocity(out + TWL_HEADER_SIZE, TWL_BODY_VELOCITY_SIZE, &vb) == 1);
  CHECK(vb.time_us == v.time_us && vb.vx_mm_s == v.vx_mm_s && vb.vy_mm_s == v.vy_mm_s && vb.wz_mrad_s == -1);
  s.time_us = 42;
  s.mode = TWL_MODE_ESTOP;
  s.faults = TWL_FAULT_ESTOP | TWL_FAULT_LOW_BATTERY;
  s.battery_mv = 11800;
  s.motor_current_ma = 65535;
  s.reserved = 0;
  CHECK(twl_encode_status(out, sizeof out, 9, &s) == TWL_HEADER_SIZE + TWL_STATUS_SIZE + 2);
  CHECK(out[3] == TWL_TYPE_STATUS && out[5] == 9);
  CHECK(twl_unpack_status(out + TWL_HEADER_SIZE, TWL_STATUS_SIZE, &sb) == 1);
  CHECK(sb.mode == TWL_MODE_ESTOP && sb.faults == s.faults && sb.battery_mv == 11800 && sb.motor_current_ma == 65535);
}

static void test_refusals(void) {
  uint8_t out[TWL_MAX_FRAME + 8];
  uint8_t payload[TWL_MAX_PAYLOAD + 1];
  twl_heartbeat_t h;
  twl_heartbeat_t hb;
  memset(payload, 0x11, sizeof payload);
  memset(&h, 0, sizeof h);
  /* Capacity one byte short: nothing written, 0 returned. */
  CHECK(twl_encode_heartbeat(out, TWL_HEADER_SIZE + TWL_HEARTBEAT_SIZE + 1, 0, &h) == 0);
  CHECK(twl_encode_frame(out, sizeof out, 0x7F, 0, payload, TWL_MAX_PAYLOAD + 1) == 0);
  CHECK(twl_encode_frame(out, sizeof out, 0x7F, 0, payload, TWL_MAX_PAYLOAD) == TWL_MAX_FRAME);
  CHECK(twl_encode_frame(NULL, 100, 0x7F, 0, payload, 1) == 0);
  /* Short payloads are refused by the unpackers. */
  CHECK(twl_unpack_heartbeat(payload, TWL_HEARTBEAT_SIZE - 1, &hb) == 0);
  CHECK(twl_payload_size(TWL_TYPE_WHEEL_ODOMETRY) == TWL_WHEEL_ODOMETRY_SIZE);
  CHECK(twl_payload_size(0x7F) == 0);
  /* An empty payload frames to header + CRC. */
  CHECK(twl_encode_frame(out, sizeof out, 0x7F, 0, NULL, 0) == TWL_HEADER_SIZE + TWL_CRC_SIZE);
}

int main(void) {
  test_crc_check_value();
  test_heartbeat_bytes();
  test_wheel_odometry_bytes_and_round_trip();
  test_extreme_values_round_trip();
  test_refusals();
  if (g_failures == 0) printf("wheel link encoder: all checks passed\n");
  return g_failures == 0 ? 0 : 1;
}
