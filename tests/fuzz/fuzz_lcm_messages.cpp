// libFuzzer target: every LCM message toposlam decodes (toposlamd's motion input, and place, place_event,
// topology and status in `toposlam listen`, with the older place and status types they fall back to). Byte 0
// picks the type; the rest is the message. When lcmArrayLengthsFit accepts it, the generated decoder must not
// throw (no length_error, no bad_alloc) and allocates at most what the message can hold.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "toposlam/platform/lcm_transport.hpp"
#include "toposlam_lcm/motion_t.hpp"
#include "toposlam_lcm/place_event_t.hpp"
#include "toposlam_lcm/place_t.hpp"
#include "toposlam_lcm/place_v1_t.hpp"
#include "toposlam_lcm/status_t.hpp"
#include "toposlam_lcm/status_v1_t.hpp"
#include "toposlam_lcm/status_v2_t.hpp"
#include "toposlam_lcm/status_v3_t.hpp"
#include "toposlam_lcm/topology_t.hpp"

namespace {

template <typename Message>
void decode(const char* kind, const std::uint8_t* data, std::size_t size) {
  if (!toposlam::lcmArrayLengthsFit(kind, data, size)) return;
  Message m{};
  try {
    (void)m.decode(data, 0, static_cast<int>(size));
  } catch (...) {
    std::abort();  // the length check let through a message the decoder cannot take
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0 || size > (1u << 20)) return 0;
  const std::uint8_t* message = data + 1;
  const std::size_t n = size - 1;
  switch (data[0] % 5) {
    case 0:  // today's type, then the old one every decoder falls back to
      decode<toposlam_lcm::place_t>("place", message, n);
      decode<toposlam_lcm::place_v1_t>("place_v1", message, n);
      break;
    case 1: decode<toposlam_lcm::place_event_t>("place_event", message, n); break;
    case 2:
      decode<toposlam_lcm::status_t>("status", message, n);
      decode<toposlam_lcm::status_v3_t>("status_v3", message, n);
      decode<toposlam_lcm::status_v2_t>("status_v2", message, n);
      decode<toposlam_lcm::status_v1_t>("status_v1", message, n);
      break;
    case 3: decode<toposlam_lcm::topology_t>("topology", message, n); break;
    default: decode<toposlam_lcm::motion_t>("motion", message, n); break;
  }
  return 0;
}
