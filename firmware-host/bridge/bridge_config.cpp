// The bridge's key table (see bridge_config.hpp): each key's default, range, unit and help in one place.
#include "bridge_config.hpp"

#include <yaml-cpp/yaml.h>

#include <functional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "toposlam/firmware/motion_link.hpp"
#include "toposlam/firmware/serial_port.hpp"

namespace toposlam::bridge {

namespace {

struct Key {
  const char* path;  // "section.key"
  const char* range;
  const char* help;
  std::function<void(const YAML::Node&, BridgeConfig&)> read;  // throws std::runtime_error(reason)
};

double number(const YAML::Node& n, double lo, double hi) {
  const double v = n.as<double>();
  if (!(v >= lo && v <= hi)) throw std::runtime_error(std::to_string(v) + " is out of range");
  return v;
}
int integer(const YAML::Node& n, int lo, int hi) {
  const int v = n.as<int>();
  if (v < lo || v > hi) throw std::runtime_error(std::to_string(v) + " is out of range");
  return v;
}

const std::vector<Key>& keys() {
  static const std::vector<Key> table = {
      {"link.protocol", "wheel | mavlink", "the controller's protocol",
       [](const YAML::Node& n, BridgeConfig& c) {
         c.protocol = n.as<std::string>();
         if (!firmware::parseProtocol(c.protocol)) throw std::runtime_error("'" + c.protocol + "' is not a protocol");
       }},
      {"link.serial", "a device path", "serial device of the controller, e.g. /dev/ttyACM0",
       [](const YAML::Node& n, BridgeConfig& c) { c.serial = n.as<std::string>(); }},
      {"link.baud", "a standard rate (9600 .. 4000000)", "serial baud rate, as the controller's UART",
       [](const YAML::Node& n, BridgeConfig& c) {
         c.baud = n.as<int>();
         if (!firmware::baudSupported(c.baud)) throw std::runtime_error(std::to_string(c.baud) + " is not a standard rate");
       }},
      {"link.udp_address", "an IPv4 address", "address to bind for MAVLink over UDP",
       [](const YAML::Node& n, BridgeConfig& c) { c.udp_address = n.as<std::string>(); }},
      {"link.udp_port", "0 .. 65535", "UDP port of a MAVLink router's output, 0 = use the serial device",
       [](const YAML::Node& n, BridgeConfig& c) { c.udp_port = integer(n, 0, 65535); }},
      {"lcm.url", "an LCM URL", "LCM provider (ttl=0 keeps it on this host)",
       [](const YAML::Node& n, BridgeConfig& c) { c.lcm_url = n.as<std::string>(); }},
      {"lcm.channel", "1 .. 255 characters", "channel of the motion_t messages",
       [](const YAML::Node& n, BridgeConfig& c) {
         c.channel = n.as<std::string>();
         if (c.channel.empty() || c.channel.size() > 255) throw std::runtime_error("bad length");
       }},
      {"status.period_s", "0 .. 3600 s", "seconds between status lines, 0 = only at exit",
       [](const YAML::Node& n, BridgeConfig& c) { c.status_period_s = number(n, 0, 3600); }},
      {"status.link_timeout_s", "0.1 .. 60 s", "no frame for this long: the link is silent or garbage",
       [](const YAML::Node& n, BridgeConfig& c) { c.link_timeout_s = number(n, 0.1, 60); }},
      {"motion.moving_speed_mps", "0 .. 10 m/s", "faster counts as moving",
       [](const YAML::Node& n, BridgeConfig& c) { c.motion.moving_speed_mps = number(n, 0, 10); }},
      {"motion.moving_turn_rps", "0 .. 10 rad/s", "turning faster counts as moving",
       [](const YAML::Node& n, BridgeConfig& c) { c.motion.moving_turn_rps = number(n, 0, 10); }},
      {"motion.max_gap_s", "0.01 .. 10 s", "velocity samples further apart are not integrated",
       [](const YAML::Node& n, BridgeConfig& c) { c.motion.max_gap_s = number(n, 0.01, 10); }},
      {"motion.max_speed_mps", "0.1 .. 1000 m/s",
       "a sample faster, or an increment longer than this speed allows, is refused and counted",
       [](const YAML::Node& n, BridgeConfig& c) { c.motion.max_speed_mps = number(n, 0.1, 1000); }},
      {"motion.max_turn_rate_rps", "0.1 .. 1000 rad/s", "a sample turning faster is refused and counted",
       [](const YAML::Node& n, BridgeConfig& c) { c.motion.max_turn_rate_rps = number(n, 0.1, 1000); }},
      {"motion.clock_tolerance_s", "0.01 .. 3600 s",
       "the controller's clock running ahead of the host's by more is refused and counted (a jump that lasts "
       "longer is a restart); the published time falling behind by more is re-estimated",
       [](const YAML::Node& n, BridgeConfig& c) { c.motion.clock_tolerance_s = number(n, 0.01, 3600); }},
  };
  return table;
}

}  // namespace

void loadBridgeConfig(const std::string& path, BridgeConfig& config) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  if (!root || root.IsNull()) return;
  if (!root.IsMap()) throw std::runtime_error(path + ": expected a map of sections (link, lcm, status, motion)");
  std::set<std::string> known;
  for (const Key& k : keys()) known.insert(k.path);
  for (const auto& section : root) {
    const std::string name = section.first.as<std::string>();
    if (!section.second.IsMap()) throw std::runtime_error(path + ": " + name + ": expected a section");
    for (const auto& entry : section.second) {
      const std::string dotted = name + "." + entry.first.as<std::string>();
      if (!known.count(dotted)) throw std::runtime_error(path + ": " + dotted + ": unknown key (see --help-config)");
    }
  }
  for (const Key& k : keys()) {
    const std::string p = k.path;
    const YAML::Node node = root[p.substr(0, p.find('.'))][p.substr(p.find('.') + 1)];
    if (!node) continue;
    try {
      k.read(node, config);
    } catch (const std::exception& e) {
      throw std::runtime_error(path + ": " + p + ": " + e.what() + ", allowed " + k.range);
    }
  }
}

void validateBridgeConfig(const BridgeConfig& c) {
  if (!firmware::parseProtocol(c.protocol))
    throw std::runtime_error("protocol '" + c.protocol + "' is not wheel or mavlink");
  if (c.serial.empty() && c.udp_port == 0)
    throw std::runtime_error("no link: give a serial device (--serial, link.serial) or a UDP port (--udp, link.udp_port)");
  if (!c.serial.empty() && c.udp_port != 0) throw std::runtime_error("give a serial device or a UDP port, not both");
  if (c.udp_port != 0 && c.protocol != "mavlink")
    throw std::runtime_error("UDP carries MAVLink from a router: use --protocol mavlink with --udp");
  if (!c.serial.empty() && !firmware::baudSupported(c.baud))
    throw std::runtime_error("baud rate " + std::to_string(c.baud) + " is not a standard rate; use one of " +
                             firmware::supportedBauds());
}

std::string describeBridgeKeys() {
  std::ostringstream out;
  for (const Key& k : keys()) out << "  " << k.path << " (" << k.range << "): " << k.help << "\n";
  return out.str();
}

}  // namespace toposlam::bridge
