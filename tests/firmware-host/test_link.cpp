// The controller line itself: missing devices, unsupported baud rates, a dead line, a line spewing
// garbage and one that hangs up, through real pseudo-terminals.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <random>
#include <string>
#include <vector>

#include "toposlam/firmware/emulator.hpp"
#include "toposlam/firmware/motion_link.hpp"
#include "toposlam/firmware/serial_port.hpp"

using namespace toposlam::firmware;

namespace {
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("GIVEN no device WHEN opened THEN the error names it and says what to check", "[firmware][link]") {
  const std::string e = errorOf([] { openSerial("/dev/toposlam-no-such-tty", 115200); });
  CHECK(e.find("/dev/toposlam-no-such-tty") != std::string::npos);
  CHECK(e.find("plugged in") != std::string::npos);
  const std::string baud = errorOf([] { openSerial("/dev/null", 115201); });
  CHECK(baud.find("115201") != std::string::npos);
  CHECK(baud.find("921600") != std::string::npos);
  const std::string notty = errorOf([] { openSerial("/dev/null", 115200); });
  CHECK(notty.find("not a serial device") != std::string::npos);
  CHECK(errorOf([] { openUdp("localhost", 14550); }).find("IPv4") != std::string::npos);
}

TEST_CASE("GIVEN a dead line WHEN the host waits THEN reads never block and the link reports silent",
          "[firmware][link]") {
  PseudoTerminal pty = openPseudoTerminal();
  auto port = openSerial(pty.slave_path, 115200);
  LinkMonitor monitor(0, 1.0);
  std::uint8_t buffer[256];
  CHECK(waitReadable(port->fd(), 20) == WaitResult::Timeout);
  CHECK(port->read(buffer).kind == ReadResult::Nothing);
  CHECK(monitor.state(500000) == LinkState::Waiting);
  CHECK(monitor.state(1500000) == LinkState::Silent);
  monitor.onBytes(1600000);
  monitor.onFrames(1600000);
  CHECK(monitor.state(2000000) == LinkState::Ok);
  CHECK(monitor.state(2700000) == LinkState::Silent);
}

TEST_CASE("GIVEN a line spewing garbage (a wrong baud rate looks like this) WHEN decoded THEN nothing is invented "
          "and the link reports garbage",
          "[firmware][link]") {
  PseudoTerminal pty = openPseudoTerminal();
  auto port = openSerial(pty.slave_path, 115200);
  // One thread writes and reads: a blocking write into a full pseudo-terminal would wait for a read that
  // can only come after it (a hang seen under ASan). Non-blocking, a full line just takes nothing.
  REQUIRE(::fcntl(pty.master, F_SETFL, ::fcntl(pty.master, F_GETFL) | O_NONBLOCK) == 0);
  std::mt19937_64 rng(3);
  std::vector<std::uint8_t> junk(64 * 1024);
  for (auto& b : junk) b = static_cast<std::uint8_t>(rng());
  // Sprinkle in sync bytes so the decoder has to work.
  for (std::size_t i = 0; i < junk.size(); i += 97) junk[i] = TWL_SYNC1;
  for (std::size_t i = 1; i < junk.size(); i += 389) junk[i] = TWL_SYNC2;
  MotionLink link(LinkProtocol::Wheel);
  LinkMonitor monitor(0, 1.0);
  std::size_t received = 0;
  std::uint64_t samples = 0;
  std::size_t written = 0;
  std::uint8_t buffer[4096];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (received < junk.size()) {
    REQUIRE(std::chrono::steady_clock::now() < deadline);  // bytes lost: fail, do not hang
    if (written < junk.size()) {
      const ssize_t n = ::write(pty.master, junk.data() + written, std::min<std::size_t>(4096, junk.size() - written));
      if (n > 0) written += static_cast<std::size_t>(n);
    }
    if (waitReadable(port->fd(), 200) != WaitResult::Readable) continue;
    const ReadResult r = port->read(buffer);
    REQUIRE(r.kind != ReadResult::Closed);
    received += r.size;
    monitor.onBytes(2000000);
    if (link.feed(std::span<const std::uint8_t>(buffer, r.size), 2000000, [&](const MotionSample&) { ++samples; }) > 0)
      monitor.onFrames(2000000);
  }
  CHECK(samples == 0);
  CHECK(link.decoder().frames == 0);
  CHECK(link.decoder().bytes_in == junk.size());
  CHECK(link.decoder().false_starts > 0);
  CHECK(monitor.state(2000000) == LinkState::Garbage);
}

TEST_CASE("GIVEN the emulator on a pseudo-terminal WHEN its master side closes THEN the reader sees a hang-up",
          "[firmware][link][emulator]") {
  PseudoTerminal pty = openPseudoTerminal();
  auto port = openSerial(pty.slave_path, 57600);
  EmulatorConfig c;
  ControllerEmulator emulator(c);
  std::vector<std::uint8_t> bytes;
  emulator.advanceTo(1.0, bytes);
  REQUIRE(::write(pty.master, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size()));
  MotionLink link(LinkProtocol::Wheel);
  std::uint64_t samples = 0;
  std::uint8_t buffer[4096];
  std::size_t received = 0;
  while (received < bytes.size() && waitReadable(port->fd(), 1000) == WaitResult::Readable) {
    const ReadResult r = port->read(buffer);
    if (r.kind != ReadResult::Data) break;
    received += r.size;
    link.feed(std::span<const std::uint8_t>(buffer, r.size), 1, [&](const MotionSample&) { ++samples; });
  }
  CHECK(received == bytes.size());
  CHECK(samples == 49);  // 50 odometry frames in 1 s, the first is the reference
  pty.closeMaster();
  // The test's own slave descriptor keeps the pty alive, so close it too, as the emulator would exit.
  ::close(pty.slave);
  pty.slave = -1;
  REQUIRE(waitReadable(port->fd(), 1000) == WaitResult::Readable);
  CHECK(port->read(buffer).kind == ReadResult::Closed);
}
