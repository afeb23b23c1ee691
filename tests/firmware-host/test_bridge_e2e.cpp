// End to end: the emulated controller writes a damaged wheel-link stream into a pseudo-terminal,
// toposlam-bridge (a child process) reads the pty's other end and publishes motion_t over real LCM UDP
// multicast (run by tests/e2e/in_netns.sh inside a private network namespace), and this test hears it.
// A MAVLink run arrives over UDP on localhost as a router would send it. Exits 77 (skipped) when LCM
// multicast does not work here.
#include <catch2/catch.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "e2e/e2e_harness.hpp"
#include "toposlam/firmware/emulator.hpp"
#include "toposlam/firmware/serial_port.hpp"
#include "toposlam/firmware/wheel_link.hpp"
#include "toposlam/platform/lcm_transport.hpp"
#include "toposlam_lcm/motion_t.hpp"

using namespace toposlam::firmware;

namespace {

const std::string kLcmUrl = "udpm://239.255.76.67:7667?ttl=0";
const std::string kChannel = "TOPOSLAM_MOTION_E2E";

struct Heard {
  std::vector<toposlam_lcm::motion_t> messages;
  int undecodable = 0;
  // Untyped subscription, decoded here: the form LcmSubscriber uses. (lcm-cpp's member-function typed
  // subscription trips GCC 12's UndefinedBehaviorSanitizer inside lcm-cpp-impl.hpp, a false report in the
  // library's header that fails the sanitizer build.)
  static void onMessage(const lcm::ReceiveBuffer* buffer, const std::string&, Heard* self) {
    toposlam_lcm::motion_t m;
    if (m.decode(buffer->data, 0, static_cast<int>(buffer->data_size)) < 0) {
      ++self->undecodable;
      return;
    }
    self->messages.push_back(m);
  }
};

/// LCM that can hear itself (else the test exits 77), subscribed to kChannel.
std::unique_ptr<lcm::LCM> lcmOrSkip(Heard& heard) {
  toposlam::e2e::skipUnlessMulticastLoopsBack(kLcmUrl);
  auto l = toposlam::openLcm(kLcmUrl);
  l->subscribeFunction(kChannel, &Heard::onMessage, &heard);
  return l;
}

/// toposlam-bridge as a child; its output is a pipe the test reads.
class Bridge : public toposlam::e2e::ChildProcess {
 public:
  explicit Bridge(const std::vector<std::string>& args) : ChildProcess(TOPOSLAM_BRIDGE_BINARY, args) {}
};

/// Handles LCM messages for `ms` milliseconds (the test must keep up: LCM drops what it cannot buffer).
void pump(lcm::LCM& l, int ms) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
  while (std::chrono::steady_clock::now() < end) l.handleTimeout(5);
}

void collect(lcm::LCM& l, Heard& heard, std::size_t expected, int timeout_ms) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (heard.messages.size() < expected && std::chrono::steady_clock::now() < end) l.handleTimeout(100);
}

}  // namespace

TEST_CASE("GIVEN the emulated wheel controller on a pty WHEN toposlam-bridge runs THEN motion_t over LCM adds up to "
          "the distance driven, stops included",
          "[firmware][bridge][e2e]") {
  Heard heard;
  auto l = lcmOrSkip(heard);
  PseudoTerminal pty = openPseudoTerminal();
  Bridge bridge({"--serial", pty.slave_path, "--baud", "115200", "--protocol", "wheel", "--lcm-url", kLcmUrl,
                 "--channel", kChannel, "--status-period", "0"});
  REQUIRE(bridge.waitForOutput("-> LCM", 5000));

  EmulatorConfig c;
  c.profile = *parseProfile("2@0.5,2@0,2@0.1667@0.3,1@0");
  c.garbage_probability = 0.1;
  c.corrupt_probability = 0.03;
  c.drop_probability = 0.02;
  c.seed = 11;
  ControllerEmulator emulator(c);
  std::vector<std::uint8_t> bytes;
  for (double t = 0.1; t <= emulator.duration() + 1e-9; t += 0.1) {  // 100 ms of traffic, then listen
    bytes.clear();
    emulator.advanceTo(t, bytes);
    REQUIRE(write(pty.master, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size()));
    pump(*l, 15);
  }
  // Every intact odometry frame but the first (the reference) becomes one message.
  const std::size_t expected = emulator.truth().motion_frames_intact - 1;
  collect(*l, heard, expected, 5000);
  CHECK(bridge.stop() == 0);
  INFO(bridge.output());
  CHECK(heard.undecodable == 0);
  REQUIRE(heard.messages.size() == expected);
  double forward = 0, turn = 0;
  int standing = 0;
  for (std::size_t i = 0; i < heard.messages.size(); ++i) {
    CHECK(heard.messages[i].sequence == static_cast<std::int64_t>(i));
    forward += heard.messages[i].forward_m;
    turn += heard.messages[i].turn_rad;
    standing += heard.messages[i].moving ? 0 : 1;
  }
  CHECK(forward == Approx(emulator.truth().distance_m).margin(0.011));
  CHECK(turn == Approx(emulator.truth().turn_rad).margin(1e-3));
  CHECK(standing > 120);  // 3 s of 7 standing at 50 Hz, less drops and damage
  CHECK(standing < 152);
  CHECK(bridge.output().find("bridge exit") != std::string::npos);
  CHECK(bridge.output().find("bad crc") != std::string::npos);
}

TEST_CASE("GIVEN MAVLink 2 ODOMETRY from a router on UDP localhost WHEN toposlam-bridge listens THEN motion_t arrives",
          "[firmware][bridge][e2e]") {
  Heard heard;
  auto l = lcmOrSkip(heard);
  const int port = 14550 + static_cast<int>(getpid() % 1000);
  Bridge bridge({"--udp", std::to_string(port), "--protocol", "mavlink", "--lcm-url", kLcmUrl, "--channel", kChannel,
                 "--status-period", "0"});
  REQUIRE(bridge.waitForOutput("-> LCM", 5000));
  EmulatorConfig c;
  c.messages = EmulatedMessages::MavlinkOdometry;
  c.profile = *parseProfile("2@1.0,1@0");
  c.rate_hz = 30;
  c.other_mavlink_traffic = true;
  ControllerEmulator emulator(c);
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
  std::vector<std::uint8_t> bytes;
  for (double t = 0.1; t <= emulator.duration() + 1e-9; t += 0.1) {  // one datagram per 100 ms of traffic
    bytes.clear();
    emulator.advanceTo(t, bytes);
    REQUIRE(sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to) ==
            static_cast<ssize_t>(bytes.size()));
    pump(*l, 15);
  }
  close(fd);
  const std::size_t expected = emulator.truth().motion_frames_intact - 1;
  collect(*l, heard, expected, 5000);
  CHECK(bridge.stop() == 0);
  INFO(bridge.output());
  CHECK(heard.undecodable == 0);
  REQUIRE(heard.messages.size() == expected);
  double forward = 0;
  for (const auto& m : heard.messages) forward += m.forward_m;
  CHECK(forward == Approx(emulator.truth().distance_m).margin(0.04));
  // One MAVLink 1 and one signed frame per heartbeat (1 Hz): skipped and counted, never published.
  CHECK(bridge.output().find("signed skipped 0,") == std::string::npos);
  CHECK(bridge.output().find("mavlink1 skipped 0,") == std::string::npos);
  CHECK(bridge.output().find("signed skipped") != std::string::npos);
}

TEST_CASE("GIVEN checksummed wheel-link frames with controller time 2^62 and an absurd wheel step among real ones WHEN "
          "toposlam-bridge reads them from a pty THEN it publishes only the real motion, on the host's clock, and "
          "counts what it refused",
          "[firmware][bridge][e2e]") {
  Heard heard;
  auto l = lcmOrSkip(heard);
  PseudoTerminal pty = openPseudoTerminal();
  Bridge bridge({"--serial", pty.slave_path, "--baud", "115200", "--protocol", "wheel", "--lcm-url", kLcmUrl,
                 "--channel", kChannel, "--status-period", "0"});
  REQUIRE(bridge.waitForOutput("-> LCM", 5000));

  // 75 real frames 20 ms apart in real time (0.5 m/s: 10 mm each), the controller's clock running with the
  // host's; after the 25th two frames at 2^62 us, after the 50th one whose left wheel steps 2^31 - 1 um.
  const auto monotonic_us = [] {
    return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  };
  const std::int64_t start_us = monotonic_us();
  std::uint8_t seq = 0;
  const auto send = [&](const twl_wheel_odometry_t& m) {
    std::uint8_t frame[64];
    const std::size_t n = twl_encode_wheel_odometry(frame, sizeof frame, seq++, &m);
    REQUIRE(n > 0);
    REQUIRE(write(pty.master, frame, n) == static_cast<ssize_t>(n));
  };
  twl_wheel_odometry_t m{0, 0, 0, 300, TWL_ODOM_DRIVING, 0};
  for (int i = 0; i < 75; ++i) {
    m.time_us = static_cast<std::uint64_t>(monotonic_us() - start_us) + 1000000;
    m.left_um = m.right_um = 10000 * i;
    send(m);
    if (i == 24) {
      twl_wheel_odometry_t poison = m;
      poison.time_us = std::uint64_t{1} << 62;
      poison.left_um = poison.right_um = m.left_um + 10000;
      send(poison);
      send(poison);
    }
    if (i == 49) {
      twl_wheel_odometry_t absurd = m;
      absurd.time_us += 10000;
      absurd.left_um = static_cast<std::int32_t>(static_cast<std::uint32_t>(m.left_um) + 0x7FFFFFFFu);  // wraps
      send(absurd);
    }
    pump(*l, 20);
  }
  // The first frame is the reference; the one after the absurd frame is the new reference.
  const std::size_t expected = 73;
  collect(*l, heard, expected, 3000);
  pump(*l, 300);  // anything more would be a message too many
  const std::int64_t end_us = monotonic_us();
  CHECK(bridge.stop() == 0);
  INFO(bridge.output());
  CHECK(heard.messages.size() == expected);
  double forward = 0, largest_step = 0;
  std::int64_t earliest = std::numeric_limits<std::int64_t>::max(), latest = 0;
  for (const auto& msg : heard.messages) {
    forward += msg.forward_m;
    largest_step = std::max(largest_step, std::abs(msg.forward_m));
    earliest = std::min(earliest, msg.utime);
    latest = std::max(latest, msg.utime);
  }
  CHECK(forward == Approx(0.73).margin(1e-9));
  CHECK(largest_step == Approx(0.01).margin(1e-9));
  CHECK(earliest >= start_us);
  CHECK(latest <= end_us);
  CHECK(bridge.output().find("refused off the clock 2,") != std::string::npos);
  CHECK(bridge.output().find("refused implausible 1,") != std::string::npos);
}

TEST_CASE("GIVEN no such device WHEN toposlam-bridge starts THEN it exits 1 (a runtime error) with an actionable message",
          "[firmware][bridge]") {
  Bridge bridge({"--serial", "/dev/toposlam-no-such-tty", "--protocol", "wheel"});
  CHECK(bridge.waitForOutput("plugged in", 5000));
  CHECK(bridge.stop() == 1);
}
