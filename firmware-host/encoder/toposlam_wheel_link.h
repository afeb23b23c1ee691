/*
 * toposlam wheel link, version 1: the controller side of the framed serial protocol between a wheeled
 * robot's motor controller and the toposlam host (byte tables in firmware-host/PROTOCOL.md).
 *
 * Portable C99 for microcontroller firmware: no allocation, no libc beyond <stdint.h> and <string.h>,
 * no floating point, no global state. Multi-byte fields are little-endian on the wire whatever the CPU.
 * The same functions unpack payloads on the host, so the byte layout has exactly one home.
 *
 * Frame:  0xA5 0x5A | version | type | length | seq | payload[length] | crc16 (low byte first)
 * CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no xor-out) over version..payload.
 *
 * Usage on the controller, e.g. at 50 Hz:
 *     uint8_t frame[TWL_MAX_FRAME];
 *     twl_wheel_odometry_t m = {now_us, left_um, right_um, 300, TWL_ODOM_DRIVING};
 *     size_t n = twl_encode_wheel_odometry(frame, sizeof frame, seq++, &m);
 *     uart_write(frame, n);
 * Thread-safety: every function is reentrant (state lives in the caller's buffers).
 */
#ifndef TOPOSLAM_WHEEL_LINK_H
#define TOPOSLAM_WHEEL_LINK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TWL_SYNC1 0xA5u
#define TWL_SYNC2 0x5Au
#define TWL_VERSION 1u
#define TWL_HEADER_SIZE 6u   /* sync1 sync2 version type length seq */
#define TWL_CRC_SIZE 2u
#define TWL_MAX_PAYLOAD 64u  /* a longer length field is impossible: the receiver resynchronises */
#define TWL_MAX_FRAME (TWL_HEADER_SIZE + TWL_MAX_PAYLOAD + TWL_CRC_SIZE)

/* Message types. */
#define TWL_TYPE_HEARTBEAT 0x01u
#define TWL_TYPE_WHEEL_ODOMETRY 0x02u
#define TWL_TYPE_BODY_VELOCITY 0x03u
#define TWL_TYPE_STATUS 0x04u

/* Payload sizes of version 1. A receiver accepts longer payloads of a known type (fields appended by a
 * later minor revision) and ignores the extra bytes; a shorter one is rejected. */
#define TWL_HEARTBEAT_SIZE 16u
#define TWL_WHEEL_ODOMETRY_SIZE 20u
#define TWL_BODY_VELOCITY_SIZE 20u
#define TWL_STATUS_SIZE 16u

/* twl_wheel_odometry_t.flags */
#define TWL_ODOM_DRIVING 0x01u /* the controller is commanding the wheels to move */

/* twl_status_t.mode */
#define TWL_MODE_IDLE 0u
#define TWL_MODE_DRIVING 1u
#define TWL_MODE_ESTOP 2u
#define TWL_MODE_FAULT 3u

/* twl_status_t.faults */
#define TWL_FAULT_OVERCURRENT 0x01u
#define TWL_FAULT_ENCODER 0x02u
#define TWL_FAULT_ESTOP 0x04u
#define TWL_FAULT_LOW_BATTERY 0x08u
#define TWL_FAULT_COMMAND_TIMEOUT 0x10u

/* All time_us fields: the controller's monotonic clock, microseconds since its boot (never steps back
 * while it runs; a smaller value means the controller restarted). */

typedef struct {
  uint64_t time_us;
  uint16_t boot_id;      /* random per controller boot: a change means it restarted */
  uint8_t fw_major;
  uint8_t fw_minor;
  uint32_t rx_errors;    /* frames the controller itself received damaged (its command link) */
} twl_heartbeat_t;

typedef struct {
  uint64_t time_us;
  int32_t left_um;       /* cumulative travel of the left wheel, micrometres, wraps modulo 2^32 */
  int32_t right_um;      /* cumulative travel of the right wheel, micrometres, wraps modulo 2^32 */
  uint16_t track_mm;     /* distance between the wheels' contact points, millimetres (> 0) */
  uint8_t flags;         /* TWL_ODOM_* */
  uint8_t reserved;      /* 0 */
} twl_wheel_odometry_t;

typedef struct {
  uint64_t time_us;
  int32_t vx_mm_s;       /* forward speed, mm/s */
  int32_t vy_mm_s;       /* leftward speed, mm/s (0 for a differential drive) */
  int32_t wz_mrad_s;     /* yaw rate, milliradians/s, counter-clockwise positive */
} twl_body_velocity_t;

typedef struct {
  uint64_t time_us;
  uint8_t mode;          /* TWL_MODE_* */
  uint8_t faults;        /* TWL_FAULT_* */
  uint16_t battery_mv;   /* 0 = not measured */
  uint16_t motor_current_ma;
  uint16_t reserved;     /* 0 */
} twl_status_t;

/* CRC-16/CCITT-FALSE of `size` bytes, continuing from `crc` (start with 0xFFFF). Check: "123456789" ->
 * 0x29B1. */
uint16_t twl_crc16(uint16_t crc, const uint8_t* data, size_t size);

/* Writes one frame carrying `payload` into `out`; returns its size, or 0 if `capacity` is too small or
 * `payload_size` exceeds TWL_MAX_PAYLOAD. */
size_t twl_encode_frame(uint8_t* out, size_t capacity, uint8_t type, uint8_t seq, const uint8_t* payload,
                        size_t payload_size);

/* Typed encoders: one frame each; return its size or 0 (capacity too small). */
size_t twl_encode_heartbeat(uint8_t* out, size_t capacity, uint8_t seq, const twl_heartbeat_t* m);
size_t twl_encode_wheel_odometry(uint8_t* out, size_t capacity, uint8_t seq, const twl_wheel_odometry_t* m);
size_t twl_encode_body_velocity(uint8_t* out, size_t capacity, uint8_t seq, const twl_body_velocity_t* m);
size_t twl_encode_status(uint8_t* out, size_t capacity, uint8_t seq, const twl_status_t* m);

/* Payload packers (payload only, no framing): write exactly TWL_<TYPE>_SIZE bytes into `p`. */
void twl_pack_heartbeat(uint8_t* p, const twl_heartbeat_t* m);
void twl_pack_wheel_odometry(uint8_t* p, const twl_wheel_odometry_t* m);
void twl_pack_body_velocity(uint8_t* p, const twl_body_velocity_t* m);
void twl_pack_status(uint8_t* p, const twl_status_t* m);

/* Payload unpackers (used by the host): return 1 and fill `m` when `size` is at least the type's
 * version-1 size, else 0. */
int twl_unpack_heartbeat(const uint8_t* p, size_t size, twl_heartbeat_t* m);
int twl_unpack_wheel_odometry(const uint8_t* p, size_t size, twl_wheel_odometry_t* m);
int twl_unpack_body_velocity(const uint8_t* p, size_t size, twl_body_velocity_t* m);
int twl_unpack_status(const uint8_t* p, size_t size, twl_status_t* m);

/* Version-1 payload size of a message type, or 0 for an unknown type. */
size_t twl_payload_size(uint8_t type);

#ifdef __cplusplus
}
#endif

#endif /* TOPOSLAM_WHEEL_LINK_H */
