// The two 16-bit CRCs of the controller links.
//   CRC-16/MCRF4XX (the "X.25" accumulate of MAVLink): poly 0x1021 reflected, init 0xFFFF, no xor-out.
//   CRC-16/CCITT-FALSE (the toposlam wheel link): poly 0x1021, init 0xFFFF, not reflected, no xor-out;
//   its implementation lives in the C encoder (twl_crc16) so controller and host share it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace toposlam::firmware {

/// One byte into a MAVLink checksum (the accumulate step of the MAVLink reference implementation).
constexpr std::uint16_t mavlinkCrcAccumulate(std::uint16_t crc, std::uint8_t byte) {
  std::uint8_t tmp = static_cast<std::uint8_t>(byte ^ (crc & 0xFF));
  tmp = static_cast<std::uint8_t>(tmp ^ (tmp << 4));
  return static_cast<std::uint16_t>((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4));
}

constexpr std::uint16_t mavlinkCrc(const std::uint8_t* data, std::size_t size, std::uint16_t crc = 0xFFFF) {
  for (std::size_t i = 0; i < size; ++i) crc = mavlinkCrcAccumulate(crc, data[i]);
  return crc;
}

}  // namespace toposlam::firmware
