// Internal to toposlam_lcm: a TOPOSLAM_PLACE message as place_t, whichever definition recorded it. Used by
// decodeLcmMessage (listen, replays) and readLoggedRun (report lcmlog:), so both read old logs alike.
#pragma once

#include <cstddef>

#include "toposlam_lcm/place_t.hpp"

namespace toposlam {

/// Decodes `data` as place_t or, failing that, as place_v1_t (recorded before match_* existed; those fields
/// then read -1 and 0). False when it is neither, or its array lengths do not fit (lcmArrayLengthsFit).
bool decodePlaceMessage(const void* data, std::size_t size, toposlam_lcm::place_t& out);

}  // namespace toposlam
