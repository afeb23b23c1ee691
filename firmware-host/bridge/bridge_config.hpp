// toposlam-bridge's config: its key table (each key's default, range, unit and help, written once in
// bridge_config.cpp) in the key-table mechanism toposlamd uses (toposlam/config/config_key.hpp), read from
// its own file, toposlam-bridge.yaml (toposlamd refuses keys it does not know), and overridden by options.
// A key's YAML path is its member's path: link.baud is BridgeConfig::link.baud.
#pragma once

#include <string>
#include <vector>

#include "toposlam/config/config_key.hpp"
#include "toposlam/config/config_reader.hpp"
#include "toposlam/firmware/motion_estimator.hpp"
#include "toposlam/firmware/motion_link.hpp"

namespace toposlam::bridge {

/// link: where the controller's bytes come from.
struct BridgeLinkConfig {
  firmware::LinkProtocol protocol = firmware::LinkProtocol::Wheel;  ///< wheel | mavlink
  std::string serial;                                               ///< device path ("" with udp_port)
  int baud = 115200;                                                ///< serial baud rate
  std::string udp_address = "127.0.0.1";  ///< address bound for MAVLink over UDP (from a router)
  int udp_port = 0;                       ///< 0 = the serial device
};

/// lcm: where the motion goes.
struct BridgeLcmConfig {
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  std::string channel = "TOPOSLAM_MOTION";
};

/// status: what is said about the link, and when.
struct BridgeStatusConfig {
  double period_s = 10;       ///< seconds between status lines, 0 = only at exit
  double link_timeout_s = 2;  ///< no frame for this long: the link is silent or garbage, s
};

struct BridgeConfig {
  BridgeLinkConfig link;
  BridgeLcmConfig lcm;
  BridgeStatusConfig status;
  firmware::MotionEstimatorConfig motion;
};

using BridgeConfigKey = BasicConfigKey<BridgeConfig>;

/// Every key, in the order of the shipped toposlam-bridge.yaml.
const std::vector<BridgeConfigKey>& bridgeConfigKeys();
const std::vector<ConfigSection>& bridgeConfigSections();

/// The config of a command line: the file at `path` ("" = the built-in defaults), then `overrides` in order,
/// then the table's ranges and cross-key checks. ConfigError "<file>: <key>: <problem>" or "command line:
/// <given_as>: <key>: <problem>". Whether the link can run is linkProblem's.
BridgeConfig bridgeCommandLineConfig(const std::string& path, const std::vector<ConfigOverride>& overrides);

/// "" when the config names a link the bridge can open (a serial device or a UDP port, not both; UDP with
/// MAVLink), else what is missing, with the options and keys that give it.
std::string linkProblem(const BridgeConfig& config);

/// Every key of `config` as YAML (--print-config); with `comments`, each key's help and allowed values.
std::string bridgeConfigYaml(const BridgeConfig& config, bool comments);
/// The shipped toposlam-bridge.yaml: the defaults, fully commented (a test keeps the file equal to it).
std::string shippedBridgeConfigYaml();

}  // namespace toposlam::bridge
