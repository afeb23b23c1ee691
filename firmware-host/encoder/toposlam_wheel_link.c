/*
 * toposlam wheel link, version 1: frame and payload encoding (see toposlam_wheel_link.h and
 * firmware-host/PROTOCOL.md). Bitwise CRC: 16 bytes of code and no table, which suits small flash.
 */
#include "toposlam_wheel_link.h"

#include <string.h>

uint16_t twl_crc16(uint16_t crc, const uint8_t* data, size_t size) {
  size_t i;
  int bit;
  for (i = 0; i < size; ++i) {
    crc = (uint16_t)(crc ^ (uint16_t)((uint16_t)data[i] << 8));
    for (bit = 0; bit < 8; ++bit)
      crc = (crc & 0x8000u) ? (uint16_t)((uint16_t)(crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
  }
  return crc;
}

/* Little-endian field writers and readers, independent of the CPU's byte order. */
static void put_u16(uint8_t* p, uint16_t v) {
  p[0] = (uint8_t)(v & 0xFFu);
  p[1] = (uint8_t)(v >> 8);
}
static void put_u32(uint8_t* p, uint32_t v) {
  int i;
  for (i = 0; i < 4; ++i) p[i] = (uint8_t)((v >> (8 * i)) & 0xFFu);
}
static void put_u64(uint8_t* p, uint64_t v) {
  int i;
  for (i = 0; i < 8; ++i) p[i] = (uint8_t)((v >> (8 * i)) & 0xFFu);
}
static uint16_t get_u16(const uint8_t* p) { return (uint16_t)(p[0] | (uint16_t)(p[1] << 8)); }
static uint32_t get_u32(const uint8_t* p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static uint64_t get_u64(const uint8_t* p) {
  return (uint64_t)get_u32(p) | ((uint64_t)get_u32(p + 4) << 32);
}
/* Two's complement conversions without implementation-defined casts of out-of-range values. */
static uint32_t from_i32(int32_t v) { return v < 0 ? (uint32_t)(-(v + 1)) ^ 0xFFFFFFFFu : (uint32_t)v; }
static int32_t to_i32(uint32_t v) {
  return v <= 0x7FFFFFFFu ? (int32_t)v : (int32_t)(-(int32_t)(~v) - 1);
}

size_t twl_payload_size(uint8_t type) {
  switch (type) {
    case TWL_TYPE_HEARTBEAT: return TWL_HEARTBEAT_SIZE;
    case TWL_TYPE_WHEEL_ODOMETRY: return TWL_WHEEL_ODOMETRY_SIZE;
    case TWL_TYPE_BODY_VELOCITY: return TWL_BODY_VELOCITY_SIZE;
    case TWL_TYPE_STATUS: return TWL_STATUS_SIZE;
    default: return 0;
  }
}

size_t twl_encode_frame(uint8_t* out, size_t capacity, uint8_t type, uint8_t seq, const uint8_t* payload,
                        size_t payload_size) {
  size_t total;
  uint16_t crc;
  if (payload_size > TWL_MAX_PAYLOAD) return 0;
  total = TWL_HEADER_SIZE + payload_size + TWL_CRC_SIZE;
  if (out == NULL || capacity < total) return 0;
  out[0] = (uint8_t)TWL_SYNC1;
  out[1] = (uint8_t)TWL_SYNC2;
  out[2] = (uint8_t)TWL_VERSION;
  out[3] = type;
  out[4] = (uint8_t)payload_size;
  out[5] = seq;
  if (payload_size > 0) memmove(out + TWL_HEADER_SIZE, payload, payload_size);
  crc = twl_crc16(0xFFFFu, out + 2, TWL_HEADER_SIZE - 2 + payload_size);
  put_u16(out + TWL_HEADER_SIZE + payload_size, crc);
  return total;
}

void twl_pack_heartbeat(uint8_t* p, const twl_heartbeat_t* m) {
  put_u64(p, m->time_us);
  put_u16(p + 8, m->boot_id);
  p[10] = m->fw_major;
  p[11] = m->fw_minor;
  put_u32(p + 12, m->rx_errors);
}

void twl_pack_wheel_odometry(uint8_t* p, const twl_wheel_odometry_t* m) {
  put_u64(p, m->time_us);
  put_u32(p + 8, from_i32(m->left_um));
  put_u32(p + 12, from_i32(m->right_um));
  put_u16(p + 16, m->track_mm);
  p[18] = m->flags;
  p[19] = m->reserved;
}

void twl_pack_body_velocity(uint8_t* p, const twl_body_velocity_t* m) {
  put_u64(p, m->time_us);
  put_u32(p + 8, from_i32(m->vx_mm_s));
  put_u32(p + 12, from_i32(m->vy_mm_s));
  put_u32(p + 16, from_i32(m->wz_mrad_s));
}

void twl_pack_status(uint8_t* p, const twl_status_t* m) {
  put_u64(p, m->time_us);
  p[8] = m->mode;
  p[9] = m->faults;
  put_u16(p + 10, m->battery_mv);
  put_u16(p + 12, m->motor_current_ma);
  put_u16(p + 14, m->reserved);
}

int twl_unpack_heartbeat(const uint8_t* p, size_t size, twl_heartbeat_t* m) {
  if (size < TWL_HEARTBEAT_SIZE) return 0;
  m->time_us = get_u64(p);
  m->boot_id = get_u16(p + 8);
  m->fw_major = p[10];
  m->fw_minor = p[11];
  m->rx_errors = get_u32(p + 12);
  return 1;
}

int twl_unpack_wheel_odometry(const uint8_t* p, size_t size, twl_wheel_odometry_t* m) {
  if (size < TWL_WHEEL_ODOMETRY_SIZE) return 0;
  m->time_us = get_u64(p);
  m->left_um = to_i32(get_u32(p + 8));
  m->right_um = to_i32(get_u32(p + 12));
  m->track_mm = get_u16(p + 16);
  m->flags = p[18];
  m->reserved = p[19];
  return 1;
}

int twl_unpack_body_velocity(const uint8_t* p, size_t size, twl_body_velocity_t* m) {
  if (size < TWL_BODY_VELOCITY_SIZE) return 0;
  m->time_us = get_u64(p);
  m->vx_mm_s = to_i32(get_u32(p + 8));
  m->vy_mm_s = to_i32(get_u32(p + 12));
  m->wz_mrad_s = to_i32(get_u32(p + 16));
  return 1;
}

int twl_unpack_status(const uint8_t* p, size_t size, twl_status_t* m) {
  if (size < TWL_STATUS_SIZE) return 0;
  m->time_us = get_u64(p);
  m->mode = p[8];
  m->faults = p[9];
  m->battery_mv = get_u16(p + 10);
  m->motor_current_ma = get_u16(p + 12);
  m->reserved = get_u16(p + 14);
  return 1;
}

/* Typed encoders pack into a local payload buffer, then frame it (no allocation, < 100 bytes of stack). */
size_t twl_encode_heartbeat(uint8_t* out, size_t capacity, uint8_t seq, const twl_heartbeat_t* m) {
  uint8_t p[TWL_HEARTBEAT_SIZE];
  twl_pack_heartbeat(p, m);
  return twl_encode_frame(out, capacity, TWL_TYPE_HEARTBEAT, seq, p, sizeof p);
}
size_t twl_encode_wheel_odometry(uint8_t* out, size_t capacity, uint8_t seq, const twl_wheel_odometry_t* m) {
  uint8_t p[TWL_WHEEL_ODOMETRY_SIZE];
  twl_pack_wheel_odometry(p, m);
  return twl_encode_frame(out, capacity, TWL_TYPE_WHEEL_ODOMETRY, seq, p, sizeof p);
}
size_t twl_encode_body_velocity(uint8_t* out, size_t capacity, uint8_t seq, const twl_body_velocity_t* m) {
  uint8_t p[TWL_BODY_VELOCITY_SIZE];
  twl_pack_body_velocity(p, m);
  return twl_encode_frame(out, capacity, TWL_TYPE_BODY_VELOCITY, seq, p, sizeof p);
}
size_t twl_encode_status(uint8_t* out, size_t capacity, uint8_t seq, const twl_status_t* m) {
  uint8_t p[TWL_STATUS_SIZE];
  twl_pack_status(p, m);
  return twl_encode_frame(out, capacity, TWL_TYPE_STATUS, seq, p, sizeof p);
}
