// toposlam-bridge's key table (firmware-host/bridge/bridge_config.cpp), in the mechanism toposlamd's table
// uses: its defaults are the structs' own, each key reads into the member of the same path, ranges and
// unknown keys are refused naming the key, and the shipped toposlam-bridge.yaml is what the table makes.
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>
#include <string>

#include "bridge_config.hpp"

using namespace toposlam;
using namespace toposlam::bridge;

namespace {

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string errorOf(const std::string& yaml) {
  BridgeConfig config;
  try {
    readConfigText(yaml, "test.yaml", bridgeConfigKeys(), config);
    if (std::string problem = configKeysProblem(bridgeConfigKeys(), config); !problem.empty()) return problem;
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

SCENARIO(
    "firmware-host: the bridge's key table holds the structs' defaults and reads each key into its member") {
  GIVEN("the default BridgeConfig and MotionEstimatorConfig") {
    const BridgeConfig defaults;
    THEN("every key's default is the member's default value") {
      for (const BridgeConfigKey& key : bridgeConfigKeys()) {
        INFO(key.path);
        CHECK(key.get(defaults) == key.default_value);
        CHECK(key.problem(key.default_value).empty());
      }
      CHECK(bridgeConfigKeys().size() == 15);
      CHECK(defaults.link.baud == 115200);
      CHECK(defaults.motion.max_gap_s == 0.5);
    }
  }
  WHEN("a file sets keys of every section") {
    BridgeConfig c;
    readConfigText(
        "link:\n  protocol: mavlink\n  udp_port: 14550\nlcm:\n  channel: MOTION_B\n"
        "status:\n  period_s: 0\nmotion:\n  max_gap_s: 0.25\n",
        "test.yaml", bridgeConfigKeys(), c);
    THEN("each lands in the member of its path; the others keep their defaults") {
      CHECK(c.link.protocol == firmware::LinkProtocol::Mavlink);
      CHECK(c.link.udp_port == 14550);
      CHECK(c.lcm.channel == "MOTION_B");
      CHECK(c.status.period_s == 0.0);
      CHECK(c.motion.max_gap_s == 0.25);
      CHECK(c.link.baud == 115200);
      CHECK(c.lcm.url == "udpm://239.255.76.67:7667?ttl=0");
      CHECK(linkProblem(c).empty());
    }
  }
}

SCENARIO("firmware-host: the bridge's config refuses what the table does not allow, naming the key") {
  CHECK_THAT(errorOf("link:\n  baud: 1000\n"),
             Catch::Contains("link.baud: 1000 is out of range, allowed 9600 .. 4000000 baud"));
  CHECK_THAT(errorOf("link:\n  baud: 100000\n"), Catch::Contains("link.baud: 100000 is not a standard rate"));
  CHECK_THAT(errorOf("link:\n  protocol: can\n"), Catch::Contains("link.protocol: 'can' is not allowed"));
  CHECK_THAT(errorOf("status:\n  link_timeout_s: 0\n"),
             Catch::Contains("status.link_timeout_s: 0 is out of range, allowed [0.1, 60] seconds"));
  CHECK_THAT(errorOf("link:\n  sreial: /dev/ttyACM0\n"),
             Catch::Contains("unknown key 'link.sreial' (line 2"));
  CHECK_THAT(errorOf("motion:\n  max_gap_s: 1\nmotion:\n  max_gap_s: 2\n"),
             Catch::Contains("duplicate key 'motion'"));
  BridgeConfig no_link;
  CHECK_THAT(linkProblem(no_link), Catch::StartsWith("no link"));
  no_link.link.udp_port = 14550;
  CHECK_THAT(linkProblem(no_link), Catch::Contains("--protocol mavlink"));
}

SCENARIO("firmware-host: command-line overrides go through the same table after the file") {
  const std::string path = std::string(TOPOSLAM_BINARY_DIR) + "/test_bridge_config.yaml";
  std::ofstream(path) << "link:\n  serial: /dev/ttyACM0\n  baud: 57600\n";
  const BridgeConfig c = bridgeCommandLineConfig(path, {{"link.baud", "921600", "--baud"}});
  CHECK(c.link.serial == "/dev/ttyACM0");
  CHECK(c.link.baud == 921600);
  CHECK_THROWS_WITH(bridgeCommandLineConfig(path, {{"link.baud", "fast", "--baud"}}),
                    Catch::StartsWith("command line: --baud: link.baud: expected an integer"));
  CHECK_THROWS_WITH(bridgeCommandLineConfig("/nonexistent/toposlam-bridge.yaml", {}),
                    Catch::Contains("cannot read the config file '/nonexistent/toposlam-bridge.yaml'"));
}

SCENARIO(
    "firmware-host: the shipped toposlam-bridge.yaml is what the table makes, and reads back to the "
    "defaults") {
  const std::string shipped =
      readFile(std::string(TOPOSLAM_SOURCE_DIR) + "/firmware-host/bridge/toposlam-bridge.yaml");
  // On a difference: `toposlam-bridge --shipped-config > firmware-host/bridge/toposlam-bridge.yaml`.
  CHECK(shipped == shippedBridgeConfigYaml());
  BridgeConfig read;
  readConfigText(shipped, "toposlam-bridge.yaml", bridgeConfigKeys(), read);
  for (const BridgeConfigKey& key : bridgeConfigKeys()) {
    INFO(key.path);
    CHECK(key.get(read) == key.default_value);
  }
  WHEN("--print-config's YAML of a changed config is read back") {
    BridgeConfig changed;
    changed.link.protocol = firmware::LinkProtocol::Mavlink;
    changed.link.udp_port = 14550;
    changed.motion.clock_tolerance_s = 0.125;
    BridgeConfig back;
    readConfigText(bridgeConfigYaml(changed, false), "printed", bridgeConfigKeys(), back);
    THEN("every key has the changed config's value") {
      for (const BridgeConfigKey& key : bridgeConfigKeys()) {
        INFO(key.path);
        CHECK(key.get(back) == key.get(changed));
      }
    }
  }
}
