// A toposlamd run from its LCM log; see the header.
#include "toposlam/platform/lcm_log_run.hpp"

#include <cmath>
#include <limits>

#include <toposlam_lcm/place_event_t.hpp>
#include <toposlam_lcm/place_t.hpp>
#include <toposlam_lcm/topology_t.hpp>

#include "place_decode.hpp"
#include "toposlam/platform/lcm_log.hpp"

namespace toposlam {

namespace {

template <typename Message>
bool decodeEvent(const LcmLogEvent& event, const std::string& kind, Message& message) {
  if (!lcmArrayLengthsFit(kind, event.data.data(), event.data.size())) return false;
  try {
    return message.decode(event.data.data(), 0, static_cast<int>(event.data.size())) >= 0;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

LoggedRun readLoggedRun(const std::string& path, const LcmChannels& channels) {
  LoggedRun run;
  LcmLogReader reader(path);
  for (LcmLogEvent event; reader.next(event);) {
    ++run.events;
    const std::string kind = channelKind(channels, event.channel);
    if (kind == "place") {
      toposlam_lcm::place_t m{};
      if (!decodePlaceMessage(event.data.data(), event.data.size(), m)) {  // old recordings too
        ++run.malformed;
        continue;
      }
      LoggedFrame f;
      f.frame = m.frame;
      f.time_s = static_cast<double>(m.utime) * 1e-6;
      f.lambda2 = m.lambda2;
      f.match_frame = m.match_frame;
      f.match_score = m.match_score;
      f.match_node = m.match_node;
      if (!std::isfinite(f.lambda2)) f.lambda2 = std::numeric_limits<double>::quiet_NaN();
      run.frames.push_back(f);
    } else if (kind == "place_event") {
      toposlam_lcm::place_event_t m{};
      if (!decodeEvent(event, kind, m)) {
        ++run.malformed;
        continue;
      }
      LoggedPlace p;
      p.place = m.place;
      p.node = m.node;
      p.is_new = m.is_new != 0;
      p.probability = m.probability;
      p.first_frame = m.first_frame;
      p.last_frame = m.last_frame;
      p.representative_frame = m.representative_frame;
      p.keypoints = m.keypoints;
      p.thumbnail_jpeg = m.jpeg;
      run.places.push_back(std::move(p));
    } else if (kind == "topology") {
      toposlam_lcm::topology_t m{};
      if (!decodeEvent(event, kind, m)) {
        ++run.malformed;
        continue;
      }
      TopologySnapshot t;
      t.map_revision = m.map_revision;
      t.probability = m.probability;
      t.particles = m.particles;
      for (const auto& n : m.nodes) {
        TopologyNode node;
        node.id = n.id;
        node.places.assign(n.places.begin(), n.places.end());
        node.representative_frames.assign(n.representative_frames.begin(), n.representative_frames.end());
        t.nodes.push_back(std::move(node));
      }
      for (const auto& e : m.edges) t.edges.push_back(TopologyEdge{e.from_node, e.to_node, e.count});
      run.topology = std::move(t);
    } else {
      ++run.other_events;
    }
  }
  return run;
}

}  // namespace toposlam
