// toposlam-bridge: the host end of the link to the robot's controller. Reads a serial device (our wheel
// link or MAVLink 2) or a localhost UDP port (MAVLink from a companion-computer router), decodes, and
// publishes each motion increment as toposlam_lcm.motion_t on TOPOSLAM_MOTION, where toposlamd (or any
// LCM node) hears it. Never blocks on the line: it polls with a short timeout, says when the link is
// silent or delivers only garbage, reopens a serial device that went away, and prints its counters
// periodically and at exit.
//
// Config: toposlam-bridge.yaml, by default $CONFIGURATION_DIRECTORY/toposlam-bridge.yaml, then the install's
// <sysconfdir>/toposlam/toposlam-bridge.yaml, then /etc/toposlam/ (as toposlamd finds toposlam.yaml), else
// the built-in defaults; options override it. --check-config and --print-config as toposlamd's.
// Also: --emulate (an emulated controller on a new pseudo-terminal) and --bench (decoder throughput).
// Exit status, as in toposlam and toposlamd: 0 done (signal or --duration), 1 runtime error (the link or
// LCM cannot be opened: a restart may help), 2 usage or config error (bad options or config; CLI11's own
// codes 105-109 are folded into 2).
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "bench.hpp"
#include "bridge_config.hpp"
#include "config_key_cli.hpp"
#include "toposlam/config/config_path.hpp"
#include "toposlam/config/config_reader.hpp"
#include "toposlam/firmware/emulator.hpp"
#include "toposlam/firmware/motion_link.hpp"
#include "toposlam/firmware/serial_port.hpp"
#include "toposlam/platform/lcm_transport.hpp"
#include "toposlam/platform/logging.hpp"
#include "toposlam_lcm/motion_t.hpp"

namespace {

using namespace toposlam;
using namespace toposlam::firmware;

std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop = true; }

std::unique_ptr<ByteStream> openLink(const bridge::BridgeConfig& c) {
  if (c.link.udp_port != 0) return openUdp(c.link.udp_address, c.link.udp_port);
  return openSerial(c.link.serial, c.link.baud);
}

const char* stateAdvice(LinkState s, const bridge::BridgeConfig& c) {
  switch (s) {
    case LinkState::Silent: return "no bytes: is the controller powered and its TX wired to our RX?";
    case LinkState::Garbage:
      return c.link.udp_port != 0 ? "datagrams but no valid MAVLink 2 frame: is the router sending MAVLink 2?"
                             : "bytes but no valid frame: wrong baud rate or wrong --protocol?";
    default: return "";
  }
}

int runBridge(const bridge::BridgeConfig& c, double duration_s) {
  std::unique_ptr<ByteStream> stream;
  try {
    stream = openLink(c);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  std::unique_ptr<lcm::LCM> lcm;
  try {
    lcm = openLcm(c.lcm.url);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  const LinkProtocol protocol = c.link.protocol;
  spdlog::info("bridge: {} ({}) -> LCM {} on {}", stream->describe(), protocolName(protocol), c.lcm.channel, c.lcm.url);

  MotionLink link(protocol, c.motion);
  const std::int64_t start_us = monotonicMicroseconds();
  LinkMonitor monitor(start_us, c.status.link_timeout_s);
  LinkState reported = LinkState::Waiting;
  std::int64_t sequence = 0;
  std::int64_t publish_failures = 0;
  std::int64_t reopens = 0;
  std::int64_t next_status_us = start_us + static_cast<std::int64_t>(c.status.period_s * 1e6);
  std::int64_t next_reopen_us = 0;
  std::vector<std::uint8_t> encoded(256);
  std::uint8_t buffer[4096];

  auto publish = [&](const MotionSample& s) {
    toposlam_lcm::motion_t m{};
    m.utime = s.utime;
    m.sequence = sequence++;
    m.forward_m = s.forward_m;
    m.lateral_m = s.lateral_m;
    m.turn_rad = s.turn_rad;
    m.linear_velocity_mps = s.linear_velocity_mps;
    m.angular_velocity_rps = s.angular_velocity_rps;
    m.moving = s.moving;
    const int size = m.getEncodedSize();
    if (encoded.size() < static_cast<std::size_t>(size)) encoded.resize(static_cast<std::size_t>(size));
    m.encode(encoded.data(), 0, size);
    if (lcm->publish(c.lcm.channel, encoded.data(), static_cast<unsigned>(size)) != 0 && publish_failures++ % 100 == 0)
      spdlog::warn("bridge: publishing on {} failed ({} so far)", c.lcm.channel, publish_failures);
  };
  auto status = [&](const char* when) {
    spdlog::info("bridge {}: link {}, published {}, publish failures {}, reopens {}; {}", when,
                 linkStateName(monitor.state(monotonicMicroseconds())), sequence, publish_failures, reopens,
                 describeCounters(link.decoder(), link.estimator().counters()));
  };

  while (!g_stop) {
    const std::int64_t now = monotonicMicroseconds();
    if (duration_s > 0 && now - start_us >= static_cast<std::int64_t>(duration_s * 1e6)) break;
    if (!stream) {
      // The serial device went away (unplugged, controller reset its USB): try again once a second.
      if (now >= next_reopen_us) {
        try {
          stream = openLink(c);
          link.resetFraming();
          ++reopens;
          spdlog::info("bridge: reopened {}", stream->describe());
        } catch (const std::exception& e) {
          next_reopen_us = now + 1000000;
        }
      }
      if (!stream) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));  // waiting for hardware, not syncing
        continue;
      }
    }
    if (waitReadable(stream->fd(), 100) == WaitResult::Readable) {
      for (int burst = 0; burst < 64; ++burst) {  // drain what is there, then check the clock again
        const ReadResult r = stream->read(buffer);
        if (r.kind == ReadResult::Nothing) break;
        if (r.kind == ReadResult::Closed) {
          spdlog::warn("bridge: {} lost ({}); reopening", stream->describe(), r.error);
          stream.reset();
          next_reopen_us = monotonicMicroseconds() + 1000000;
          break;
        }
        const std::int64_t t = monotonicMicroseconds();
        monitor.onBytes(t);
        if (link.feed(std::span<const std::uint8_t>(buffer, r.size), t, publish) > 0) monitor.onFrames(t);
      }
    }
    const std::int64_t t = monotonicMicroseconds();
    const LinkState state = monitor.state(t);
    if (state != reported) {
      if (state == LinkState::Ok)
        spdlog::info("bridge: link ok ({} frames so far)", link.decoder().frames);
      else if (state != LinkState::Waiting)
        spdlog::warn("bridge: link {} for {} s: {}", linkStateName(state), c.status.link_timeout_s, stateAdvice(state, c));
      reported = state;
    }
    if (c.status.period_s > 0 && t >= next_status_us) {
      status("status");
      next_status_us = t + static_cast<std::int64_t>(c.status.period_s * 1e6);
    }
  }
  status("exit");
  return 0;
}

struct EmulateOptions {
  std::string messages = "wheel-odometry";
  std::string profile = "20@0.5,10@0,15@0.1667,10@0,3@0@0.5236,10@0.5,10@0";
  double rate_hz = 50;
  double drop = 0, corrupt = 0, garbage = 0;
  std::uint64_t seed = 1;
  bool loop = false;
  bool other_mavlink = false;
  std::string dropouts;  // "S-E,S-E"
};

int runEmulator(const EmulateOptions& o) {
  EmulatorConfig c;
  auto messages = parseEmulatedMessages(o.messages);
  std::string error;
  auto profile = parseProfile(o.profile, &error);
  if (!messages) {
    spdlog::error("--emulate {}: use wheel-odometry, body-velocity, mavlink-odometry or mavlink-local-position", o.messages);
    return 2;
  }
  if (!profile) {
    spdlog::error("--profile: {}", error);
    return 2;
  }
  c.messages = *messages;
  c.profile = *profile;
  c.rate_hz = o.rate_hz;
  c.drop_probability = o.drop;
  c.corrupt_probability = o.corrupt;
  c.garbage_probability = o.garbage;
  c.seed = o.seed;
  c.other_mavlink_traffic = o.other_mavlink;
  if (!o.dropouts.empty()) {
    std::stringstream all(o.dropouts);
    std::string item;
    while (std::getline(all, item, ',')) {
      Dropout d;
      if (std::sscanf(item.c_str(), "%lf-%lf", &d.start_s, &d.end_s) != 2 || d.end_s <= d.start_s) {
        spdlog::error("--dropouts: '{}' is not START-END in seconds", item);
        return 2;
      }
      c.dropouts.push_back(d);
    }
  }
  std::optional<PseudoTerminal> opened;
  try {
    opened.emplace(openPseudoTerminal());
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  PseudoTerminal& pty = *opened;
  std::printf("%s\n", pty.slave_path.c_str());
  std::fflush(stdout);
  spdlog::info("emulator: {} at {} Hz on {} ({:.0f} s profile{})", o.messages, o.rate_hz, pty.slave_path,
               ControllerEmulator(c).duration(), o.loop ? ", looping" : "");
  auto stream = adoptDescriptor(pty.master, "pty master");
  pty.master = -1;
  std::vector<std::uint8_t> bytes;
  do {
    ControllerEmulator emulator(c);
    const auto start = std::chrono::steady_clock::now();
    while (!g_stop) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      bytes.clear();
      emulator.advanceTo(std::min(t, emulator.duration()), bytes);
      if (!bytes.empty() && !stream->write(bytes)) {
        spdlog::error("emulator: writing to the pty failed");
        return 1;
      }
      if (t >= emulator.duration()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));  // real-time pacing of the emulated line
    }
    const EmulatorTruth& truth = emulator.truth();
    spdlog::info("emulator: drove {:.3f} m, turned {:.3f} rad; {} motion frames ({} intact), {} dropped, {} corrupted, "
                 "{} garbage bytes",
                 truth.distance_m, truth.turn_rad, truth.motion_frames, truth.motion_frames_intact, truth.frames_dropped,
                 truth.frames_corrupted, truth.garbage_bytes);
  } while (o.loop && !g_stop);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"toposlam-bridge: robot controller link (wheel link or MAVLink 2) -> TOPOSLAM_MOTION over LCM"};
  app.set_version_flag("--version", "toposlam-bridge " TOPOSLAM_VERSION);  // project(VERSION), the package version
  std::string config_path;
  double duration = 0, bench_seconds = 1.0;
  bool bench = false, help_config = false, check_only = false, print_config = false, shipped_config = false;
  std::string log_level = "info";
  EmulateOptions emulate;
  std::string emulate_kind;
  app.add_option("-c,--config", config_path,
                 "config file (YAML; keys: --help-config). Default: " +
                     toposlam::defaultConfigPath("toposlam-bridge.yaml") + " if it exists, else built-in defaults");
  // The options that set a key come from the key table (bridge_config.cpp), as toposlamd's do.
  const cli::ConfigKeyOptions<bridge::BridgeConfig> key_options(app, bridge::bridgeConfigKeys());
  std::vector<std::string> sets;
  app.add_option("--set", sets,
                 "set any key of the config: --set KEY=VALUE (repeatable; keys and values as in the YAML, "
                 "--help-config), applied after the file and the options above")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  app.add_flag("--check-config", check_only, "validate the config, print the result and exit");
  app.add_flag("--print-config", print_config,
               "print the effective config (file, defaults and options) as YAML with every key, and exit");
  app.add_flag("--shipped-config", shipped_config,
               "print the shipped toposlam-bridge.yaml (the defaults, every key with its help) and exit");
  app.add_option("--duration", duration, "stop after this many seconds (0 = until SIGINT/SIGTERM)");
  app.add_flag("--help-config", help_config, "list the config keys");
  app.add_option("--log-level", log_level, "log level: trace, debug, info, warn or error (default info)")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  app.add_flag("--bench", bench, "print decoder throughput (MB/s) and exit");
  app.add_option("--bench-seconds", bench_seconds, "seconds per protocol for --bench");
  app.add_option("--emulate", emulate_kind,
                 "emulate a controller on a new pseudo-terminal (printed on stdout): wheel-odometry, body-velocity, "
                 "mavlink-odometry, mavlink-local-position");
  app.add_option("--profile", emulate.profile, "emulator speed profile D@V[@W],... (s, m/s, rad/s)");
  app.add_option("--rate", emulate.rate_hz, "emulator motion messages per second")->check(CLI::Range(1.0, 2000.0));
  app.add_option("--drop", emulate.drop, "emulator: probability a frame is lost")->check(CLI::Range(0.0, 1.0));
  app.add_option("--corrupt", emulate.corrupt, "emulator: probability a frame gets a bit error")->check(CLI::Range(0.0, 1.0));
  app.add_option("--garbage", emulate.garbage, "emulator: probability of random bytes before a frame")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--dropouts", emulate.dropouts, "emulator: silent intervals START-END,... (s)");
  app.add_option("--seed", emulate.seed, "emulator random seed");
  app.add_flag("--loop", emulate.loop, "emulator: repeat the profile until stopped");
  app.add_flag("--other-mavlink", emulate.other_mavlink, "emulator: add MAVLink 1, signed and unknown frames");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints the help, the version or the usage error
    return code == 0 ? 0 : 2;      // CLI11's own codes (105-109, ...) are usage errors: 2
  }
  // Logs go to stderr (the journal's format under systemd): stdout carries --emulate's pty path and --bench's
  // figures.
  toposlam::configureLogging("toposlam-bridge", *toposlam::parseLogLevel(log_level));

  signal(SIGINT, onSignal);
  signal(SIGTERM, onSignal);
  signal(SIGPIPE, SIG_IGN);
  if (help_config) {
    std::printf("toposlam-bridge config keys (YAML sections link, lcm, status, motion):\n");
    for (const bridge::BridgeConfigKey& key : bridge::bridgeConfigKeys())
      std::printf("  %s (%s): %s\n", key.path.c_str(), key.rangeText().c_str(), key.help.c_str());
    return 0;
  }
  if (shipped_config) {
    std::printf("%s", bridge::shippedBridgeConfigYaml().c_str());
    return 0;
  }
  if (bench) return bridge::runBenchmark(bench_seconds);
  if (!emulate_kind.empty()) {
    emulate.messages = emulate_kind;
    return runEmulator(emulate);
  }
  bridge::BridgeConfig config;
  try {
    const bool explicit_config = !config_path.empty();
    if (!explicit_config) config_path = toposlam::defaultConfigPath("toposlam-bridge.yaml");
    const bool read_file = explicit_config || std::filesystem::exists(config_path);
    std::vector<ConfigOverride> given;
    // --udp alone replaces the file's serial device: a UDP link has none.
    if (key_options.given("link.udp_port") && !key_options.given("link.serial"))
      given.push_back({"link.serial", "", "--udp"});
    for (const ConfigOverride& o : key_options.overrides()) given.push_back(o);
    for (const std::string& set : sets)
      given.push_back(parseSetAssignment(configKeySpecs(bridge::bridgeConfigKeys()), set, "link.baud=57600",
                                         "toposlam-bridge --help-config"));
    config = bridge::bridgeCommandLineConfig(read_file ? config_path : std::string(), given);
    if (!read_file) config_path = "(built-in defaults)";
    if (print_config) {
      std::printf("# toposlam-bridge's effective config: %s%s\n%s", config_path.c_str(),
                  given.empty() ? "" : " and the options", bridge::bridgeConfigYaml(config, false).c_str());
      return 0;
    }
    if (const std::string problem = bridge::linkProblem(config); !problem.empty())
      throw ConfigError(config_path + ": " + problem);
    if (check_only) {
      std::printf("toposlam-bridge: config OK: %s\n", config_path.c_str());
      return 0;
    }
    spdlog::info("toposlam-bridge: config {}", config_path);
  } catch (const std::exception& e) {
    spdlog::error("toposlam-bridge: {}", e.what());
    return 2;
  }
  return runBridge(config, duration);
}
