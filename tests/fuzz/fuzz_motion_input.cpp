// libFuzzer target: toposlamd's motion input, as the LCM receive thread and the segmentation thread see
// it. The input is a run of records [receiver clock step, length, message]: the clock advances by the
// step (in 10 ms), the message is decoded as a TOPOSLAM_MOTION motion_t (decodeLcmMessage) and, when it
// decodes, given to the MotionGate stamped with the receiver's clock; the gate is then asked about a frame
// at that clock. Checked after every record: each sample is taken or refused (never lost), a refused
// sample leaves the state as it was, distance and turn stay finite and never shrink, and a frame can be
// standing only while motion is known.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "toposlam/platform/lcm_transport.hpp"
#include "toposlam/segmentation/motion_gate.hpp"

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > (1u << 16)) return 0;
  toposlam::MotionGate gate(toposlam::MotionGateConfig{});
  const toposlam::LcmChannels channels;
  double receiver_s = 1000.0;
  std::int64_t given = 0;
  for (std::size_t at = 0; at + 2 <= size;) {
    receiver_s += 0.01 * data[at];
    const std::size_t length = std::min<std::size_t>(data[at + 1], size - at - 2);
    const std::uint8_t* message = data + at + 2;
    at += 2 + length;
    toposlam::ReceivedMessage m;
    if (!toposlam::decodeLcmMessage("motion", channels.motion, message, length, m)) continue;
    const double distance_before = gate.distanceM();
    const std::int64_t samples_before = gate.samples();
    const toposlam::MotionState state_before = gate.at(receiver_s);
    const bool taken =
        gate.addSample(m.motion_time_s, m.motion_distance_m, m.motion_speed_mps, m.motion_turn_rate_rps, receiver_s);
    ++given;
    check(gate.samples() + gate.rejectedSamples() == given);
    check(taken == (gate.samples() == samples_before + 1));
    const toposlam::MotionState state = gate.at(receiver_s);
    check(std::isfinite(gate.distanceM()) && gate.distanceM() >= distance_before);
    check(std::isfinite(state.turned_rad) && state.turned_rad >= 0.0);
    check(!state.standing || state.known);
    if (!taken) {
      check(gate.distanceM() == distance_before);
      check(state.known == state_before.known && state.standing == state_before.standing);
    } else {
      // Taken: its time was within the tolerance of the receiver's clock, so motion is known now.
      check(state.known);
    }
  }
  return 0;
}
