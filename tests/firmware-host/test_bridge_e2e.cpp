// End to end: the emulated controller writes a damaged wheel-link stream into a pseudo-terminal,
// toposlam-bridge (a child process) reads the pty's other end and publishes motion_t over real LCM UDP
// multicast (run by tests/e2e/in_netns.sh inside a private network namespace), and this test hears it.
// A MAVLink run arrives over UDP on localhost as a router would send it. Exits 77 (skipped) when LCM
// multicast does not work here.
#include <catch2/catch.hpp>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "toposlam/firmware/emulator.hpp"
#include "toposlam/firmware/serial_port.hpp"
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

/// LCM that can hear itself, or exit 77.
std::unique_ptr<lcm::LCM> lcmOrSkip(Heard& heard) {
  std::unique_ptr<lcm::LCM> l;
  try {
    l = toposlam::openLcm(kLcmUrl);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skipped: %s\n", e.what());
    std::_Exit(77);
  }
  l->subscribeFunction(kChannel, &Heard::onMessage, &heard);
  toposlam_lcm::motion_t probe{};
  probe.sequence = -1;
  l->publish(kChannel, &probe);
  if (l->handleTimeout(1000) <= 0 || heard.messages.empty()) {
    std::fprintf(stderr, "skipped: LCM multicast does not loop back here\n");
    std::_Exit(77);
  }
  heard.messages.clear();
  return l;
}

/// toposlam-bridge as a child; its stderr is a pipe we read.
class Bridge {
 public:
  explicit Bridge(const std::vector<std::string>& args) {
    int fds[2];
    REQUIRE(pipe(fds) == 0);
    pid_ = fork();
    if (pid_ == 0) {
      dup2(fds[1], 2);
      close(fds[0]);
      std::vector<char*> argv;
      const std::string binary = TOPOSLAM_BRIDGE_BINARY;
      argv.push_back(const_cast<char*>(binary.c_str()));
      for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(binary.c_str(), argv.data());
      _exit(127);
    }
    close(fds[1]);
    err_ = fds[0];
  }
  ~Bridge() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    close(err_);
  }
  /// Reads stderr until `text` appears or timeout_ms passes.
  bool waitFor(const std::string& text, int timeout_ms) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    while (log_.find(text) == std::string::npos) {
      const int left = static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(end - std::chrono::steady_clock::now()).count());
      if (left <= 0) return false;
      pollfd p{err_, POLLIN, 0};
      if (poll(&p, 1, left) <= 0) continue;
      char buffer[4096];
      const ssize_t n = read(err_, buffer, sizeof buffer);
      if (n <= 0) return log_.find(text) != std::string::npos;
      log_.append(buffer, static_cast<std::size_t>(n));
    }
    return true;
  }
  int stop() {
    kill(pid_, SIGTERM);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    waitFor("\n\n", 200);  // collect the rest of the log
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  const std::string& log() const { return log_; }

 private:
  pid_t pid_ = -1;
  int err_ = -1;
  std::string log_;
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
  REQUIRE(bridge.waitFor("-> LCM", 5000));

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
  INFO(bridge.log());
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
  CHECK(bridge.log().find("bridge exit") != std::string::npos);
  CHECK(bridge.log().find("bad crc") != std::string::npos);
}

TEST_CASE("GIVEN MAVLink 2 ODOMETRY from a router on UDP localhost WHEN toposlam-bridge listens THEN motion_t arrives",
          "[firmware][bridge][e2e]") {
  Heard heard;
  auto l = lcmOrSkip(heard);
  const int port = 14550 + static_cast<int>(getpid() % 1000);
  Bridge bridge({"--udp", std::to_string(port), "--protocol", "mavlink", "--lcm-url", kLcmUrl, "--channel", kChannel,
                 "--status-period", "0"});
  REQUIRE(bridge.waitFor("-> LCM", 5000));
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
  INFO(bridge.log());
  CHECK(heard.undecodable == 0);
  REQUIRE(heard.messages.size() == expected);
  double forward = 0;
  for (const auto& m : heard.messages) forward += m.forward_m;
  CHECK(forward == Approx(emulator.truth().distance_m).margin(0.04));
  // One MAVLink 1 and one signed frame per heartbeat (1 Hz): skipped and counted, never published.
  CHECK(bridge.log().find("signed skipped 0,") == std::string::npos);
  CHECK(bridge.log().find("mavlink1 skipped 0,") == std::string::npos);
  CHECK(bridge.log().find("signed skipped") != std::string::npos);
}

TEST_CASE("GIVEN no such device WHEN toposlam-bridge starts THEN it exits 3 with an actionable message",
          "[firmware][bridge]") {
  Bridge bridge({"--serial", "/dev/toposlam-no-such-tty", "--protocol", "wheel"});
  CHECK(bridge.waitFor("plugged in", 5000));
  CHECK(bridge.stop() == 3);
}
