// libFuzzer target: the controller links' decoders (docs/firmware-host.md), the host side of a serial line
// or UDP port anyone can write garbage into. Byte 0 picks the protocol the MotionLink decodes, byte 1 the
// piece sizes the rest is fed in (a serial read returns any number of bytes). Both decoders see every
// input; each must account for every byte (skipped + verified frames + still buffered = fed), and the
// decoded messages go through the motion estimator as in the bridge.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "toposlam/firmware/mavlink.hpp"
#include "toposlam/firmware/motion_link.hpp"
#include "toposlam/firmware/wheel_link.hpp"

using namespace toposlam::firmware;

namespace {

template <class Decoder>
void checkAccounting(const Decoder& d) {
  const DecoderCounters& c = d.counters();
  if (c.bytes_in != c.bytes_skipped + c.frame_bytes + d.buffered()) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2 || size > (1u << 20)) return 0;
  MotionLink link((data[0] & 1) != 0 ? LinkProtocol::Mavlink : LinkProtocol::Wheel);
  wheel::Decoder wheel_decoder;
  mavlink::Decoder mavlink_decoder;
  std::size_t piece = 1 + data[1] % 64;
  std::int64_t host_us = 1'000'000;
  std::uint64_t samples = 0;
  for (std::size_t at = 2; at < size;) {
    const std::size_t n = std::min(piece, size - at);
    const std::span<const std::uint8_t> bytes(data + at, n);
    wheel_decoder.feed(bytes, [](const wheel::Frame& f) { (void)wheel::decode(f); });
    mavlink_decoder.feed(bytes, [](const mavlink::Frame& f) { (void)mavlink::decode(f); });
    link.feed(bytes, host_us, [&samples](const MotionSample&) { ++samples; });
    checkAccounting(wheel_decoder);
    checkAccounting(mavlink_decoder);
    at += n;
    host_us += 2'000;
    piece = 1 + (piece * 7 + 3) % 64;
  }
  if (samples > link.decoder().frames) std::abort();  // at most one motion sample per verified frame
  return 0;
}
