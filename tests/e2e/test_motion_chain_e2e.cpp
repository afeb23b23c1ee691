// End to end through the whole motion chain of issue 17: the emulated wheel controller (ControllerEmulator,
// what `toposlam-bridge --emulate` runs) writes its damaged link into a pseudo-terminal in real time; the
// real toposlam-bridge reads the pty and publishes TOPOSLAM_MOTION over LCM multicast; the real toposlamd,
// mapping the simulated office at 25 fps, uses that motion. Checked: the bridge published one message per
// intact odometry frame and the daemon received them; its status goes none -> used -> lost; the frames
// taken while the emulated robot stands (and only those) are left out of segmentation and counted.
//
// The halves are tested on their own too: tests/firmware-host/test_bridge_e2e.cpp (emulator -> bridge ->
// LCM) and the "Robot motion over LCM" scenario of test_toposlamd_e2e.cpp (a test publisher -> toposlamd).
// Runs inside in_netns.sh's private network namespace; exits 77 where LCM multicast or pseudo-terminals
// are missing.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iomanip>
#include <optional>
#include <string>
#include <vector>

#include "e2e_harness.hpp"
#include "toposlam/firmware/emulator.hpp"
#include "toposlam/firmware/serial_port.hpp"
#include "toposlam/platform/lcm_transport.hpp"

namespace fs = std::filesystem;
using namespace toposlam;

namespace {

const std::string kLcmUrl = "udpm://239.255.76.67:7667?ttl=0";
constexpr double kFps = 25.0;
// Driving 3 s at 0.5 m/s, standing 5 s, turning on the spot 2 s at 0.5 rad/s (moving: the view sweeps
// the room), driving 2 s.
const std::string kProfile = "3@0.5,5@0,2@0@0.5,2@0.5";
constexpr double kStopS = 5.0;
// toposlamd's defaults (config/toposlam.yaml, segmentation.motion): slower than 0.05 m/s and turning
// slower than 0.1 rad/s for 1 s is standing.
constexpr double kStandingSpeedMps = 0.05;
constexpr double kStandingTurnRateRps = 0.1;
constexpr double kStandingAfterS = 1.0;

firmware::PseudoTerminal pseudoTerminalOrSkip() {
  try {
    return firmware::openPseudoTerminal();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skipped: no pseudo-terminal here: %s\n", e.what());
    std::_Exit(77);
  }
}

/// The "published N" of toposlam-bridge's exit line, -1 when absent.
std::int64_t bridgePublished(const std::string& log) {
  const std::size_t exit_line = log.find("bridge exit:");
  const std::string key = "published ";
  const std::size_t at = log.find(key, exit_line == std::string::npos ? log.size() : exit_line);
  return at == std::string::npos ? -1 : std::stoll(log.substr(at + key.size()));
}

/// The emulated robot's stop as the bridge published it: from the first slow sample to the first sample
/// after it that moves or turns, CLOCK_MONOTONIC microseconds (both -1 when there is none).
struct Stop {
  double from_us = -1, to_us = -1;
};
Stop stopOf(const std::vector<ReceivedMessage>& motions) {
  Stop stop;
  for (const ReceivedMessage& m : motions) {
    const bool slow = m.motion_speed_mps < kStandingSpeedMps && m.motion_turn_rate_rps < kStandingTurnRateRps;
    if (slow && stop.from_us < 0) stop.from_us = m.motion_time_s * 1e6;
    if (!slow && stop.from_us >= 0) {
      stop.to_us = m.motion_time_s * 1e6;
      break;
    }
  }
  return stop;
}

/// One run of the chain, shared by the sections below (Catch re-enters the scenario once per THEN; the
/// programs run once).
struct ChainRun {
  int daemon_code = -1, bridge_code = -1;
  bool writes_ok = true, emulator_done = false;
  firmware::EmulatorTruth truth;
  std::string bridge_output;
  e2e::Heard heard;
  std::vector<std::int64_t> status_received_us;  ///< when each status arrived here, CLOCK_MONOTONIC
  double run_s = 0;
};

const ChainRun& chainRun() {
  static const ChainRun run = [] {
    ChainRun r;
    e2e::skipUnlessMulticastLoopsBack(kLcmUrl);
    firmware::PseudoTerminal pty = pseudoTerminalOrSkip();
    const fs::path dir = e2e::freshDirectory("motion-chain");
    auto subscriber = e2e::subscribe(kLcmUrl, r.heard);
    e2e::ChildProcess::Options daemon_output;
    daemon_output.log_file = dir / "toposlamd.log";
    e2e::ChildProcess daemon(
        TOPOSLAMD_BINARY,
        {"--source", "sim:office?route=loop2&rate=" + std::to_string(static_cast<int>(kFps)), "--overflow",
         "block", "--map", (dir / "map.tsm").string(), "--no-map-load", "--lcm-url", kLcmUrl},
        daemon_output);
    e2e::ChildProcess bridge(TOPOSLAM_BRIDGE_BINARY,
                             {"--serial", pty.slave_path, "--baud", "115200", "--protocol", "wheel",
                              "--lcm-url", kLcmUrl, "--status-period", "0"});
    if (!bridge.waitForOutput("-> LCM", 5000)) {
      r.bridge_output = bridge.output();
      return r;
    }
    firmware::EmulatorConfig config;
    config.profile = *firmware::parseProfile(kProfile);
    config.garbage_probability = 0.05;
    config.corrupt_probability = 0.02;
    config.drop_probability = 0.02;
    config.seed = 17;
    firmware::ControllerEmulator emulator(config);

    // The emulator writes what its controller sent up to now whenever the loop comes round (every few ms:
    // the daemon's 25 place messages and the bridge's 50 motion messages a second wake it), like
    // `toposlam-bridge --emulate`'s 10 ms pacing. It starts once the daemon's first status is heard (its
    // LCM is up) and falls silent at the profile's end; once a status then says the motion is lost,
    // toposlamd is stopped (or after 45 s: a failure).
    const auto started = std::chrono::steady_clock::now();
    std::optional<std::chrono::steady_clock::time_point> emulator_from;
    bool sent_stop = false;
    std::vector<std::uint8_t> bytes;
    r.daemon_code = e2e::listenUntilExit(*subscriber, daemon, 60.0, [&] {
      const auto now = std::chrono::steady_clock::now();
      while (r.status_received_us.size() < r.heard.statuses.size())
        r.status_received_us.push_back(monotonicMicroseconds());
      if (!emulator_from && !r.heard.statuses.empty()) emulator_from = now;
      if (emulator_from && !r.emulator_done) {
        const double t =
            std::min(std::chrono::duration<double>(now - *emulator_from).count(), emulator.duration());
        bytes.clear();
        emulator.advanceTo(t, bytes);
        if (!bytes.empty())
          r.writes_ok &= write(pty.master, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size());
        r.emulator_done = t >= emulator.duration();
      }
      bridge.output();  // keeps its pipe drained
      const bool lost = r.emulator_done && !r.heard.statuses.empty() &&
                        r.heard.statuses.back().json.find("\"motion_state\":\"lost\"") != std::string::npos;
      if (!sent_stop && (lost || now - started > std::chrono::seconds(45))) {
        daemon.terminate();
        sent_stop = true;
      }
    });
    while (r.status_received_us.size() < r.heard.statuses.size())
      r.status_received_us.push_back(monotonicMicroseconds());
    r.bridge_code = bridge.stop();
    r.bridge_output = bridge.output();
    r.truth = emulator.truth();
    r.run_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return r;
  }();
  return run;
}

}  // namespace

SCENARIO("The whole motion chain: emulated controller -> pty -> toposlam-bridge -> LCM -> toposlamd") {
  GIVEN(
      "toposlamd on the simulated office at 25 fps, toposlam-bridge on a pty, and the emulated wheel "
      "controller on a damaged line: driving 3 s, standing 5 s, turning on the spot 2 s, driving 2 s, "
      "silent") {
    const ChainRun& run = chainRun();
    const e2e::Heard& heard = run.heard;
    const e2e::MotionStatusHistory status = e2e::motionStatusHistory(heard.statuses);
    INFO("bridge output:\n" << run.bridge_output);
    INFO("first status " << (heard.statuses.empty() ? "-" : heard.statuses.front().json));
    INFO("last status " << (heard.statuses.empty() ? "-" : heard.statuses.back().json));
    THEN("both programs exit 0 and every intact odometry frame became one motion_t the daemon received") {
      CHECK(run.writes_ok);
      CHECK(run.emulator_done);
      CHECK(run.daemon_code == 0);
      CHECK(run.bridge_code == 0);
      const std::int64_t published = bridgePublished(run.bridge_output);
      INFO("emulator: " << run.truth.motion_frames << " odometry frames, " << run.truth.motion_frames_intact
                        << " intact, " << run.truth.frames_dropped << " dropped, "
                        << run.truth.frames_corrupted << " corrupted, " << run.truth.garbage_bytes
                        << " garbage bytes; bridge published " << published << "; daemon received "
                        << status.messages << "; heard here " << heard.motions.size() << "; run " << run.run_s
                        << " s");
      // The first intact odometry frame is the reference, every later one an increment.
      CHECK(published == static_cast<std::int64_t>(run.truth.motion_frames_intact) - 1);
      CHECK(published > 500);  // 12 s at 50 Hz, less drops and damage
      // UDP on loopback may lose a datagram under load; the daemon counts what it received.
      CHECK(status.messages <= published);
      CHECK(status.messages >= published - published / 20);
    }
    THEN("the status says none before the motion, used while it arrives, lost once the emulator is silent") {
      REQUIRE_FALSE(heard.statuses.empty());
      INFO(heard.statuses.size() << " statuses; the first saying used: #" << status.first_used
                                 << ", the first saying lost: #" << status.first_lost);
      CHECK(status.first_says_none);
      CHECK(status.first_used > 0);
      CHECK(status.first_lost > status.first_used);
    }
    THEN(
        "the frames of the stop are left out, as many as the stop's length and the frame rate give, and no "
        "others") {
      // The stop as the bridge published it is the emulator's.
      const Stop stop = stopOf(heard.motions);
      REQUIRE(stop.from_us > 0);
      REQUIRE(stop.to_us > stop.from_us);
      CHECK((stop.to_us - stop.from_us) * 1e-6 == Approx(kStopS).margin(0.1));
      // Standing from standing_after_s into the stop to its end: 4 s, 100 frames at 25 fps. A loaded
      // machine captures fewer or bunched frames, so the expectation is the frames the daemon captured in
      // that interval (the place messages' capture times).
      const std::int64_t captured =
          e2e::framesCapturedIn(heard.places, stop.from_us + kStandingAfterS * 1e6, stop.to_us);
      const std::int64_t standing = status.standing_frames;
      // The count before the robot had stood for standing_after_s, and once the stop was over (1 s later,
      // for the last standing frame to reach a status).
      std::int64_t before = 0;
      std::optional<std::int64_t> after;
      for (std::size_t i = 0; i < heard.statuses.size(); ++i) {
        const auto t = static_cast<double>(run.status_received_us[i]);
        const std::int64_t n = e2e::integerField(heard.statuses[i], "motion_standing_frames");
        if (t < stop.from_us + kStandingAfterS * 1e6) before = std::max(before, n);
        if (!after && t > stop.to_us + 1e6) after = n;
      }
      INFO("stop " << std::fixed << std::setprecision(3) << (stop.to_us - stop.from_us) * 1e-6
                   << " s; standing frames " << standing << " (nominal "
                   << static_cast<int>((kStopS - kStandingAfterS) * kFps)
                   << "), frames captured while standing " << captured << ", before the stop " << before
                   << ", right after it " << (after ? std::to_string(*after) : "-"));
      CHECK(standing >= static_cast<std::int64_t>(kFps));  // at least 1 s of the 4 s
      CHECK(std::abs(standing - captured) <= std::max<std::int64_t>(5, captured / 10));
      CHECK(before == 0);
      REQUIRE(after.has_value());
      CHECK(*after == standing);  // turning on the spot and driving on added none
    }
  }
}
