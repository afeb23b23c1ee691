// Frame-level loop closures: see frame_loop_closures.hpp.
#include "toposlam/topology/frame_loop_closures.hpp"

#include <algorithm>
#include <stdexcept>

namespace toposlam {

std::vector<FrameMatch> matchFramesToEarlierVisits(const std::vector<std::int64_t>& place_of_frame,
                                                   const std::vector<std::int64_t>& node_of_place,
                                                   const std::vector<double>& probability_of_place,
                                                   const std::vector<std::shared_ptr<const Fingerprint>>& fingerprints,
                                                   const SimilarityMeasure& similarity, int min_gap) {
  if (fingerprints.size() != place_of_frame.size() || probability_of_place.size() != node_of_place.size())
    throw std::invalid_argument("matchFramesToEarlierVisits: sizes differ");
  const auto places = static_cast<std::int64_t>(node_of_place.size());
  const auto node = [&](std::int64_t p) { return node_of_place[static_cast<std::size_t>(p)]; };
  // First place of the visit each place belongs to (a visit: consecutive places on one node).
  std::vector<std::int64_t> visit_start(node_of_place.size(), 0);
  for (std::int64_t p = 1; p < places; ++p)
    visit_start[static_cast<std::size_t>(p)] = node(p) == node(p - 1) ? visit_start[static_cast<std::size_t>(p - 1)] : p;
  // Frames of every place, in time order.
  std::vector<std::vector<std::int64_t>> frames_of_place(node_of_place.size());
  for (std::size_t f = 0; f < place_of_frame.size(); ++f) {
    const std::int64_t p = place_of_frame[f];
    if (p >= 0 && p < places && fingerprints[f]) frames_of_place[static_cast<std::size_t>(p)].push_back(static_cast<std::int64_t>(f));
  }
  std::vector<FrameMatch> out(place_of_frame.size());
  std::vector<std::int64_t> candidates;  // places to search, ascending, no duplicates
  std::int64_t candidates_for = -1;      // the visit start they were built for
  for (std::size_t f = 0; f < place_of_frame.size(); ++f) {
    const std::int64_t p = place_of_frame[f];
    if (p < 0 || p >= places || !fingerprints[f] || node(p) < 0) continue;
    const std::int64_t start = visit_start[static_cast<std::size_t>(p)];
    if (start != candidates_for) {
      // Earlier visits of this node, with the place before and after each (its neighbours in the topology,
      // where a border drawn a little differently on the other visit puts the same view).
      candidates.clear();
      for (std::int64_t e = 0; e < start; ++e) {
        if (node(e) != node(p)) continue;
        for (std::int64_t c = std::max<std::int64_t>(0, e - 1); c <= std::min(start - 1, e + 1); ++c)
          if (candidates.empty() || candidates.back() < c) candidates.push_back(c);
      }
      candidates_for = start;
    }
    FrameMatch& best = out[f];
    for (const std::int64_t c : candidates) {
      for (const std::int64_t other : frames_of_place[static_cast<std::size_t>(c)]) {
        if (static_cast<std::int64_t>(f) - other < min_gap) continue;
        const double s = similarity.symmetricSimilarity(*fingerprints[static_cast<std::size_t>(other)], *fingerprints[f]);
        if (s > best.similarity) {
          best.match_frame = other;
          best.similarity = s;
        }
      }
    }
    if (best.match_frame >= 0) best.score = best.similarity * probability_of_place[static_cast<std::size_t>(p)];
  }
  return out;
}

}  // namespace toposlam
