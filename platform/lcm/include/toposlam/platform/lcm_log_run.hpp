// What a recorded LCM log of toposlamd says about its run: every place estimate (frame, time, lambda2), every
// place event (its frames, node, thumbnail) and the last topology, read with LcmLogReader and decoded with
// the toposlam_lcm types. `toposlam listen --from lcmlog:FILE --run-folder DIR` and `toposlam report
// lcmlog:FILE` turn it into a run folder (docs/run-folder.md).
//
// Thread-safety: a pure function of the file.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "toposlam/pipeline/stages.hpp"
#include "toposlam/platform/lcm_transport.hpp"

namespace toposlam {

struct LoggedFrame {
  std::int64_t frame = 0;
  double time_s = 0.0;  ///< place_t.utime: the frame's capture time from its source, seconds
  double lambda2 = std::numeric_limits<double>::quiet_NaN();
  std::int64_t match_frame = -1;  ///< place_t.match_frame: the earlier frame it is back at, -1: none
  double match_score = 0.0;
  int match_node = -1;
};

struct LoggedPlace {
  int place = -1;
  int node = -1;          ///< as the place event said (the last topology may have moved it since)
  bool is_new = false;
  double probability = 0.0;
  std::int64_t first_frame = 0, last_frame = 0, representative_frame = 0;
  int keypoints = 0;
  std::vector<std::uint8_t> thumbnail_jpeg;
};

struct LoggedRun {
  std::vector<LoggedFrame> frames;  ///< in log order (a publisher that fell behind dropped some: gaps)
  std::vector<LoggedPlace> places;  ///< in log order
  std::optional<TopologySnapshot> topology;  ///< the last one in the log
  std::int64_t events = 0;          ///< events read
  std::int64_t other_events = 0;    ///< on channels that are none of toposlam's (status, motion included)
  std::int64_t malformed = 0;       ///< on toposlam's channels but not decodable
};

/// Reads the whole log; LcmLogError (file, byte offset) when it is corrupt or truncated.
LoggedRun readLoggedRun(const std::string& path, const LcmChannels& channels);

}  // namespace toposlam
