// toposlam-bridge's config: one key table (dotted key, default, range, unit, help) read from YAML
// (toposlam-bridge.yaml, its own file: toposlamd refuses keys it does not know) and overridden by options.
#pragma once

#include <string>
#include <vector>

#include "toposlam/firmware/motion_estimator.hpp"

namespace toposlam::bridge {

struct BridgeConfig {
  std::string protocol = "wheel";       ///< link.protocol: wheel | mavlink
  std::string serial;                   ///< link.serial: device path ("" with udp_port)
  int baud = 115200;                    ///< link.baud
  std::string udp_address = "127.0.0.1";///< link.udp_address (MAVLink from a router)
  int udp_port = 0;                     ///< link.udp_port, 0 = serial
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";  ///< lcm.url
  std::string channel = "TOPOSLAM_MOTION";                  ///< lcm.channel
  double status_period_s = 10;          ///< status.period_s, 0 = only at exit
  double link_timeout_s = 2;            ///< status.link_timeout_s
  firmware::MotionEstimatorConfig motion;  ///< motion.moving_speed_mps, moving_turn_rps, max_gap_s
};

/// Reads `path` over the defaults in `config`; throws std::runtime_error naming the file, the key and the
/// allowed range.
void loadBridgeConfig(const std::string& path, BridgeConfig& config);
/// Checks the combination (a serial device or a UDP port, a known protocol...); throws with the problem.
void validateBridgeConfig(const BridgeConfig& config);
/// The key table as text (for --help-config and docs).
std::string describeBridgeKeys();

}  // namespace toposlam::bridge
