// The bridge's key table (see bridge_config.hpp): each key's default, range, unit and help in one place;
// the reader, the range checks, the options, --print-config and the shipped file are made from it.
#include "bridge_config.hpp"

#include "toposlam/firmware/serial_port.hpp"

namespace toposlam::bridge {

namespace {

// The member a key lands in, for const and non-const configs alike.
#define AT(member) [](auto& c) -> auto& { return c.member; }

struct BridgeKeyTable : ConfigKeyBuilders<BridgeConfig> {
  static std::vector<BridgeConfigKey> makeKeys() {
    const BridgeConfig d;  // the defaults are the structs' own
    std::vector<BridgeConfigKey> k;
    k.push_back(
        choice("link.protocol", AT(link.protocol), d.link.protocol,
               {{"wheel", firmware::LinkProtocol::Wheel}, {"mavlink", firmware::LinkProtocol::Mavlink}},
               "the controller's protocol: wheel (the toposlam wheel link, firmware-host/PROTOCOL.md) or "
               "mavlink (MAVLink 2)")
            .withOption("--protocol"));
    k.push_back(text("link.serial", AT(link.serial), d.link.serial, 0, 4096,
                     "serial device of the controller, e.g. /dev/ttyACM0 or /dev/serial/by-id/...; \"\" with "
                     "link.udp_port")
                    .withOption("--serial"));
    k.push_back(integer("link.baud", AT(link.baud), d.link.baud, 9600, 4000000, "baud",
                        "serial baud rate, as the controller's UART")
                    .withNote("a standard rate")
                    .withOption("--baud")
                    .withCrossCheck([](const BridgeConfig& c) -> std::string {
                      if (firmware::baudSupported(c.link.baud)) return "";
                      return std::to_string(c.link.baud) + " is not a standard rate, allowed " +
                             firmware::supportedBauds();
                    }));
    k.push_back(text("link.udp_address", AT(link.udp_address), d.link.udp_address, 1, 255,
                     "address to bind for MAVLink over UDP from a router (mavlink-router, MAVProxy)"));
    k.push_back(integer("link.udp_port", AT(link.udp_port), d.link.udp_port, 0, 65535, "",
                        "UDP port of a MAVLink router's output")
                    .withNote("0 = use the serial device")
                    .withOption("--udp"));
    k.push_back(text("lcm.url", AT(lcm.url), d.lcm.url, 1, 4096,
                     "LCM provider URL, the same as toposlamd's (ttl=0 keeps it on this host)")
                    .withOption("--lcm-url"));
    k.push_back(text("lcm.channel", AT(lcm.channel), d.lcm.channel, 1, 255,
                     "channel of the motion_t messages: toposlamd's lcm.channels.motion")
                    .withOption("--channel"));
    k.push_back(real("status.period_s", AT(status.period_s), d.status.period_s, 0, 3600, "seconds",
                     "seconds between status lines")
                    .withNote("0 = only at exit")
                    .withOption("--status-period"));
    k.push_back(real("status.link_timeout_s", AT(status.link_timeout_s), d.status.link_timeout_s, 0.1, 60,
                     "seconds", "no valid frame for this long: the link is reported silent or garbage"));
    k.push_back(real("motion.moving_speed_mps", AT(motion.moving_speed_mps), d.motion.moving_speed_mps, 0, 10,
                     "m/s", "faster counts as moving"));
    k.push_back(real("motion.moving_turn_rps", AT(motion.moving_turn_rps), d.motion.moving_turn_rps, 0, 10,
                     "rad/s", "turning faster counts as moving"));
    k.push_back(real("motion.max_gap_s", AT(motion.max_gap_s), d.motion.max_gap_s, 0.01, 10, "seconds",
                     "body-velocity samples further apart are not integrated"));
    k.push_back(
        real("motion.max_speed_mps", AT(motion.max_speed_mps), d.motion.max_speed_mps, 0.1, 1000, "m/s",
             "a sample faster, or an increment longer than this speed allows, is refused and counted"));
    k.push_back(real("motion.max_turn_rate_rps", AT(motion.max_turn_rate_rps), d.motion.max_turn_rate_rps,
                     0.1, 1000, "rad/s", "a sample turning faster is refused and counted"));
    k.push_back(
        real("motion.clock_tolerance_s", AT(motion.clock_tolerance_s), d.motion.clock_tolerance_s, 0.01, 3600,
             "seconds",
             "the controller's clock running ahead of the host's by more is refused and counted (a jump "
             "that lasts longer is a restart); the published time falling behind by more is re-estimated"));
    return k;
  }
};

#undef AT

}  // namespace

const std::vector<BridgeConfigKey>& bridgeConfigKeys() {
  static const std::vector<BridgeConfigKey> keys = BridgeKeyTable::makeKeys();
  return keys;
}

const std::vector<ConfigSection>& bridgeConfigSections() {
  static const std::vector<ConfigSection> sections = {
      {"link", "the controller's link: a serial device, or MAVLink over UDP from a router"},
      {"lcm", "where the motion is published (toposlamd listens there)"},
      {"status", "the link's state and the counters, in the log"},
      {"motion", "motion estimation from the controller's messages (refused samples are counted)"},
  };
  return sections;
}

BridgeConfig bridgeCommandLineConfig(const std::string& path, const std::vector<ConfigOverride>& overrides) {
  BridgeConfig config;
  const std::vector<BridgeConfigKey>& keys = bridgeConfigKeys();
  if (!path.empty()) {
    readConfigText(readConfigFile(path, "toposlam-bridge.yaml"), path, keys, config);
    if (std::string problem = configKeysProblem(keys, config); !problem.empty())
      throw ConfigError(path + ": " + problem);
  }
  for (const ConfigOverride& o : overrides) {
    try {
      setConfigKey(keys, config, o.path, o.text);
    } catch (const ConfigError& e) {
      throw ConfigError("command line: " + o.given_as + ": " + e.what());
    }
  }
  if (std::string problem = configKeysProblem(keys, config); !problem.empty())
    throw ConfigError("command line: " + problem);
  return config;
}

std::string linkProblem(const BridgeConfig& c) {
  if (c.link.serial.empty() && c.link.udp_port == 0)
    return "no link: give a serial device (--serial, link.serial) or a UDP port (--udp, link.udp_port)";
  if (!c.link.serial.empty() && c.link.udp_port != 0) return "give a serial device or a UDP port, not both";
  if (c.link.udp_port != 0 && c.link.protocol != firmware::LinkProtocol::Mavlink)
    return "UDP carries MAVLink from a router: use --protocol mavlink (link.protocol) with --udp";
  return "";
}

std::string bridgeConfigYaml(const BridgeConfig& config, bool comments) {
  return configKeysYaml(bridgeConfigKeys(), bridgeConfigSections(), config, comments);
}

std::string shippedBridgeConfigYaml() {
  return "# toposlam-bridge.yaml: the config of toposlam-bridge (installed as "
         "/etc/toposlam/toposlam-bridge.yaml;\n"
         "# with systemd, ConfigurationDirectory=toposlam makes it "
         "$CONFIGURATION_DIRECTORY/toposlam-bridge.yaml).\n"
         "#\n"
         "# Made from the bridge's key table (firmware-host/bridge/bridge_config.cpp); test_bridge_config "
         "checks\n"
         "# that this file is what the table makes, so change a key's help or default there.\n"
         "# Every key is optional: an absent key keeps the default shown. Unknown or repeated keys, wrong "
         "types\n"
         "# and out-of-range values are refused at start with the key's dotted name and its range. Options\n"
         "# (--serial, --baud, ..., --set KEY=VALUE) override the file. Set link.serial (or link.udp_port)\n"
         "# before starting the service. Check a file: toposlam-bridge --check-config -c FILE; every key's\n"
         "# effective value: toposlam-bridge --print-config -c FILE.\n" +
         bridgeConfigYaml(BridgeConfig{}, true);
}

}  // namespace toposlam::bridge
