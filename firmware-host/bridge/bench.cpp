// toposlam-bridge --bench: decoder throughput on one core over a stream of mixed garbage and frames
// (about half the bytes garbage, full of start bytes), for both protocols. Prints MB/s; fails nothing.
#include "bench.hpp"

#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

#include "toposlam/firmware/emulator.hpp"
#include "toposlam/firmware/motion_link.hpp"

namespace toposlam::bridge {

namespace {

std::vector<std::uint8_t> mixedStream(firmware::EmulatedMessages kind, std::size_t target_bytes) {
  firmware::EmulatorConfig c;
  c.messages = kind;
  c.rate_hz = 1000;
  c.profile = {{1e6, 0.5, 0.1}};
  c.garbage_probability = 1.0;  // 1..64 random bytes before every frame
  c.corrupt_probability = 0.05;
  c.other_mavlink_traffic = true;
  c.seed = 1;
  firmware::ControllerEmulator emulator(c);
  std::vector<std::uint8_t> bytes;
  bytes.reserve(target_bytes + 4096);
  for (double t = 1; bytes.size() < target_bytes; t += 1) emulator.advanceTo(t, bytes);
  return bytes;
}

void run(const char* name, firmware::EmulatedMessages kind, firmware::LinkProtocol protocol, double seconds) {
  const std::vector<std::uint8_t> bytes = mixedStream(kind, 8u << 20);
  firmware::MotionLink link(protocol);
  double forward = 0;
  std::uint64_t fed = 0;
  const auto start = std::chrono::steady_clock::now();
  double elapsed = 0;
  do {
    for (std::size_t at = 0; at < bytes.size(); at += 4096) {
      const std::size_t n = std::min<std::size_t>(4096, bytes.size() - at);
      link.feed(std::span<const std::uint8_t>(bytes.data() + at, n), 0,
                [&](const firmware::MotionSample& s) { forward += s.forward_m; });
    }
    fed += bytes.size();
    elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  } while (elapsed < seconds);
  const firmware::DecoderCounters& d = link.decoder();
  std::printf("%-24s %8.1f MB/s  %10.0f frames/s  skipped %4.1f %% of bytes  (%llu MiB in %.2f s)\n", name,
              static_cast<double>(fed) / elapsed / 1e6, static_cast<double>(d.frames) / elapsed,
              100.0 * static_cast<double>(d.bytes_skipped) / static_cast<double>(d.bytes_in),
              static_cast<unsigned long long>(fed >> 20), elapsed);
  if (forward < 0) std::printf("(driven backwards?)\n");  // keeps the estimator's work observable
}

}  // namespace

int runBenchmark(double seconds) {
  std::printf("decoder throughput, one core, mixed garbage and frames (4 KiB reads):\n");
  run("wheel link (odometry)", firmware::EmulatedMessages::WheelOdometry, firmware::LinkProtocol::Wheel, seconds);
  run("MAVLink 2 (ODOMETRY)", firmware::EmulatedMessages::MavlinkOdometry, firmware::LinkProtocol::Mavlink, seconds);
  run("MAVLink 2 (LOCAL_POS)", firmware::EmulatedMessages::MavlinkLocalPosition, firmware::LinkProtocol::Mavlink,
      seconds);
  return 0;
}

}  // namespace toposlam::bridge
