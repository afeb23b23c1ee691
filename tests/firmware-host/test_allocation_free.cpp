// The decoders and the motion estimator must not touch the heap per frame: the candidate buffer is a
// member array and messages are values. This executable interposes malloc (glibc) to count calls made
// while a flag is set, as tests/segmentation's allocation test does. Sanitizer builds replace malloc
// themselves, so there the test only runs the stream.
#include <catch2/catch.hpp>

#include <atomic>
#include <cstddef>
#include <memory>
#include <vector>

#include "toposlam/firmware/emulator.hpp"
#include "toposlam/firmware/motion_link.hpp"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define TOPOSLAM_COUNT_MALLOC 0
#else
#define TOPOSLAM_COUNT_MALLOC 1
#endif

namespace {
std::atomic<long> g_mallocs{0};
std::atomic<bool> g_counting{false};
}  // namespace

#if TOPOSLAM_COUNT_MALLOC
extern "C" void* __libc_malloc(std::size_t size);  // NOLINT: glibc's own allocator entry point
extern "C" void* malloc(std::size_t size) {        // NOLINT: deliberate interposition
  if (g_counting.load(std::memory_order_relaxed)) g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
#endif

using namespace toposlam::firmware;

TEST_CASE("GIVEN damaged streams of either protocol WHEN decoded into motion THEN no frame allocates",
          "[firmware][allocation]") {
  for (EmulatedMessages kind : {EmulatedMessages::WheelOdometry, EmulatedMessages::BodyVelocity,
                                EmulatedMessages::MavlinkOdometry, EmulatedMessages::MavlinkLocalPosition}) {
    EmulatorConfig c;
    c.messages = kind;
    c.profile = *parseProfile("5@0.5,2@0,3@0.2@0.3");
    c.garbage_probability = 0.2;
    c.corrupt_probability = 0.05;
    c.other_mavlink_traffic = true;
    ControllerEmulator emulator(c);
    std::vector<std::uint8_t> bytes;
    bytes.reserve(1 << 20);
    emulator.advanceTo(emulator.duration(), bytes);
    const LinkProtocol protocol =
        kind == EmulatedMessages::WheelOdometry || kind == EmulatedMessages::BodyVelocity ? LinkProtocol::Wheel
                                                                                          : LinkProtocol::Mavlink;
    MotionLink link(protocol);
    double forward = 0;
    g_counting = true;
    const long before = g_mallocs.load();
    for (std::size_t at = 0; at < bytes.size(); at += 61) {
      const std::size_t n = std::min<std::size_t>(61, bytes.size() - at);
      link.feed(std::span<const std::uint8_t>(bytes.data() + at, n), static_cast<std::int64_t>(at),
                [&](const MotionSample& s) { forward += s.forward_m; });
    }
    const long during = g_mallocs.load() - before;
    g_counting = false;
    INFO("messages " << static_cast<int>(kind));
    CHECK(link.decoder().frames > 400);
    CHECK(forward > 2.0);
#if TOPOSLAM_COUNT_MALLOC
    CHECK(during == 0);
#else
    (void)during;
#endif
  }
#if TOPOSLAM_COUNT_MALLOC
  SECTION("the counter itself works") {
    g_counting = true;
    const long before = g_mallocs.load();
    auto probe = std::make_unique<std::vector<int>>(100);
    g_counting = false;
    CHECK(g_mallocs.load() > before);
  }
#else
  WARN("allocation counting is off under sanitizers");
#endif
}
