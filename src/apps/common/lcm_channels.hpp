// The LCM channel names of the config (lcm.*_channel) as the transport takes them: one place for the
// programs that publish or listen (toposlamd, `toposlam listen`, `toposlam report lcmlog:`,
// `toposlam-bench pipeline`). Header only: each of them links the config and LCM libraries already.
#pragma once

#include "toposlam/config/daemon_config.hpp"
#include "toposlam/platform/lcm_transport.hpp"

namespace toposlam {

inline LcmChannels channelsOf(const LcmSettings& lcm) {
  LcmChannels c;
  c.place = lcm.place_channel;
  c.place_event = lcm.place_event_channel;
  c.topology = lcm.topology_channel;
  c.status = lcm.status_channel;
  c.motion = lcm.motion_channel;
  return c;
}

}  // namespace toposlam
