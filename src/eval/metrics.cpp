// Evaluation measures (see metrics.hpp and docs/evaluation.md for the definitions).
#include "toposlam/eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>

namespace toposlam::eval {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
double ratio(double a, double b) { return b > 0 ? a / b : kNaN; }
}  // namespace

std::vector<double> defaultThresholds() { return {0.5, 0.6, 0.7, 0.8, 0.9}; }

std::vector<LocalisationRow> localisationTable(const std::vector<LocalisationPrediction>& predictions,
                                               const std::vector<double>& thresholds) {
  std::vector<LocalisationRow> rows;
  for (double t : thresholds) {
    LocalisationRow row;
    row.threshold = t;
    for (const auto& p : predictions) {
      if (!(p.probability >= t)) continue;
      ++row.images;
      if (p.predicted == p.truth) ++row.correct;
    }
    row.precision = ratio(row.correct, row.images);
    rows.push_back(row);
  }
  return rows;
}

void LoopClosureTruth::set(int i, int j, std::int8_t s) {
  const auto n = static_cast<std::size_t>(size);
  state[static_cast<std::size_t>(i) * n + static_cast<std::size_t>(j)] = s;
  state[static_cast<std::size_t>(j) * n + static_cast<std::size_t>(i)] = s;
}

std::int64_t LoopClosureTruth::positives() const {
  std::int64_t count = 0;
  for (int i = 0; i < size; ++i) {
    for (int j = 0; j < i; ++j) count += at(i, j) == 1 ? 1 : 0;
  }
  return count;
}

LoopClosureTruth truthFromMatrix(const LoopClosureMatrix& matrix, int min_gap) {
  LoopClosureTruth truth;
  truth.size = matrix.size;
  truth.state.assign(static_cast<std::size_t>(matrix.size) * static_cast<std::size_t>(matrix.size), 0);
  for (int i = 0; i < matrix.size; ++i) {
    for (int j = 0; j <= i; ++j) {
      truth.set(i, j, i - j <= min_gap ? std::int8_t{-1} : static_cast<std::int8_t>(matrix.at(i, j) ? 1 : 0));
    }
  }
  return truth;
}

std::vector<int> visitIds(const std::vector<int>& labels) {
  std::vector<int> visit(labels.size(), -1);
  int current = -1, last_label = -1;
  for (std::size_t f = 0; f < labels.size(); ++f) {
    if (labels[f] < 0) continue;
    if (labels[f] != last_label) {
      ++current;
      last_label = labels[f];
    }
    visit[f] = current;
  }
  return visit;
}

LoopClosureTruth truthFromRooms(const std::vector<int>& rooms, int min_gap) {
  const int n = static_cast<int>(rooms.size());
  const std::vector<int> visit = visitIds(rooms);
  LoopClosureTruth truth;
  truth.size = n;
  truth.state.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(n), -1);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < i; ++j) {
      const auto ii = static_cast<std::size_t>(i), jj = static_cast<std::size_t>(j);
      if (i - j <= min_gap || rooms[ii] < 0 || rooms[jj] < 0 || visit[ii] == visit[jj]) continue;
      truth.set(i, j, rooms[ii] == rooms[jj] ? std::int8_t{1} : std::int8_t{0});
    }
  }
  return truth;
}

std::vector<ScoredPair> pairsFromAssignments(const std::vector<int>& node_of_frame,
                                             const std::vector<double>& probability_of_frame) {
  // A predicted visit is a run of frames on one node (frames without a node do not end it), just as a
  // true visit is a run of frames in one room: only pairs from different visits claim a loop closure.
  const std::vector<int> visit = visitIds(node_of_frame);
  std::map<int, std::vector<int>> frames_of_node;
  for (std::size_t f = 0; f < node_of_frame.size(); ++f) {
    if (node_of_frame[f] >= 0) frames_of_node[node_of_frame[f]].push_back(static_cast<int>(f));
  }
  std::vector<ScoredPair> pairs;
  for (const auto& [node, frames] : frames_of_node) {
    for (std::size_t a = 0; a < frames.size(); ++a) {
      for (std::size_t b = 0; b < a; ++b) {
        const auto later = static_cast<std::size_t>(frames[a]);
        if (visit[later] == visit[static_cast<std::size_t>(frames[b])]) continue;
        const double p = later < probability_of_frame.size() ? probability_of_frame[later] : 1.0;
        pairs.push_back(ScoredPair{frames[a], frames[b], p});
      }
    }
  }
  return pairs;
}

PrCurve precisionRecall(const LoopClosureTruth& truth, const std::vector<ScoredPair>& pairs) {
  PrCurve curve;
  curve.positives = truth.positives();
  std::vector<std::pair<double, bool>> scored;  // score, is a true positive
  for (const ScoredPair& p : pairs) {
    if (p.i < 0 || p.j < 0 || p.i >= truth.size || p.j >= truth.size) {
      throw std::out_of_range("loop-closure pair (" + std::to_string(p.i) + ", " + std::to_string(p.j) +
                              ") is outside the ground truth of " + std::to_string(truth.size) + " frames");
    }
    const std::int8_t s = truth.at(p.i, p.j);
    if (s < 0 || p.i == p.j) continue;
    scored.emplace_back(p.score, s == 1);
  }
  curve.predicted = static_cast<std::int64_t>(scored.size());
  std::sort(scored.begin(), scored.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::int64_t tp = 0, fp = 0;
  double previous_recall = 0.0;
  for (std::size_t k = 0; k < scored.size(); ++k) {
    if (scored[k].second)
      ++tp;
    else
      ++fp;
    if (k + 1 < scored.size() && scored[k + 1].first == scored[k].first)
      continue;  // one point per distinct score
    PrPoint point;
    point.threshold = scored[k].first;
    point.true_positives = tp;
    point.false_positives = fp;
    point.precision = static_cast<double>(tp) / static_cast<double>(tp + fp);
    point.recall =
        curve.positives > 0 ? static_cast<double>(tp) / static_cast<double>(curve.positives) : kNaN;
    if (curve.positives > 0) {
      curve.average_precision += (point.recall - previous_recall) * point.precision;
      previous_recall = point.recall;
    }
    if (fp == 0 && curve.positives > 0 && point.recall > curve.recall_at_full_precision) {
      curve.recall_at_full_precision = point.recall;
      curve.threshold_at_full_precision = point.threshold;
    }
    curve.points.push_back(point);
  }
  if (curve.positives == 0) curve.average_precision = kNaN;
  return curve;
}

std::vector<BoundaryInterval> roomBoundaries(const std::vector<int>& rooms,
                                             const std::vector<std::int64_t>& traversal_starts) {
  const std::set<std::int64_t> starts(traversal_starts.begin(), traversal_starts.end());
  std::vector<BoundaryInterval> out;
  int last_room = -1;
  std::int64_t last_room_end = -1;
  for (std::size_t i = 0; i < rooms.size(); ++i) {
    const auto f = static_cast<std::int64_t>(i);
    if (starts.count(f) > 0) last_room = -1;
    const int r = rooms[i];
    if (r < 0) continue;
    if (last_room >= 0 && r != last_room) out.push_back(BoundaryInterval{last_room_end + 1, f});
    last_room = r;
    last_room_end = f;
  }
  return out;
}

BoundaryScore scoreBoundaries(const std::vector<std::int64_t>& predicted_cuts,
                              const std::vector<BoundaryInterval>& truth, int tolerance) {
  BoundaryScore score;
  score.tolerance = tolerance;
  score.predicted = static_cast<int>(predicted_cuts.size());
  score.truth = static_cast<int>(truth.size());
  std::vector<std::tuple<std::int64_t, std::size_t, std::size_t>> candidates;  // distance, predicted, truth
  for (std::size_t p = 0; p < predicted_cuts.size(); ++p) {
    for (std::size_t g = 0; g < truth.size(); ++g) {
      const std::int64_t c = predicted_cuts[p];
      const std::int64_t distance = std::max<std::int64_t>({0, truth[g].from - c, c - truth[g].to});
      if (distance <= tolerance) candidates.emplace_back(distance, p, g);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> used_p(predicted_cuts.size(), false), used_g(truth.size(), false);
  double offset_sum = 0.0;
  for (const auto& [distance, p, g] : candidates) {
    if (used_p[p] || used_g[g]) continue;
    used_p[p] = used_g[g] = true;
    ++score.matched;
    const std::int64_t c = predicted_cuts[p];
    offset_sum +=
        static_cast<double>(c < truth[g].from ? c - truth[g].from : (c > truth[g].to ? c - truth[g].to : 0));
  }
  score.mean_offset = ratio(offset_sum, score.matched);
  score.precision = ratio(score.matched, score.predicted);
  score.recall = ratio(score.matched, score.truth);
  score.f1 = score.precision + score.recall > 0
                 ? 2 * score.precision * score.recall / (score.precision + score.recall)
                 : (score.matched == 0 && score.predicted + score.truth > 0 ? 0.0 : kNaN);
  return score;
}

int traversalOf(std::int64_t frame, const std::vector<std::int64_t>& traversal_starts) {
  int t = 0;
  for (std::size_t k = 1; k < traversal_starts.size(); ++k) {
    if (frame >= traversal_starts[k]) t = static_cast<int>(k);
  }
  return t;
}

namespace {
/// Visits per (room, traversal): runs of one room inside a traversal, doorway frames ignored.
std::map<int, std::vector<int>> roomVisits(const std::vector<int>& rooms,
                                           const std::vector<std::int64_t>& starts, int traversals) {
  std::map<int, std::vector<int>> visits;
  int last_room = -1, last_traversal = -1;
  for (std::size_t i = 0; i < rooms.size(); ++i) {
    const int t = traversalOf(static_cast<std::int64_t>(i), starts);
    if (t != last_traversal) {
      last_room = -1;
      last_traversal = t;
    }
    const int r = rooms[i];
    if (r < 0 || r == last_room) continue;
    auto& v = visits[r];
    v.resize(static_cast<std::size_t>(traversals), 0);
    ++v[static_cast<std::size_t>(t)];
    last_room = r;
  }
  return visits;
}
int traversalCount(const std::vector<std::int64_t>& starts) {
  return std::max<int>(1, static_cast<int>(starts.size()));
}
}  // namespace

std::vector<TraversalCount> placesPerTraversal(const std::vector<std::int64_t>& representatives,
                                               const std::vector<int>& rooms,
                                               const std::vector<std::int64_t>& traversal_starts) {
  const int traversals = traversalCount(traversal_starts);
  std::vector<TraversalCount> out(static_cast<std::size_t>(traversals));
  for (int t = 0; t < traversals; ++t) out[static_cast<std::size_t>(t)].traversal = t;
  for (std::int64_t rep : representatives)
    ++out[static_cast<std::size_t>(traversalOf(rep, traversal_starts))].places;
  for (const auto& [room, per] : roomVisits(rooms, traversal_starts, traversals)) {
    for (int t = 0; t < traversals; ++t)
      out[static_cast<std::size_t>(t)].room_visits += per[static_cast<std::size_t>(t)];
  }
  return out;
}

ConsistencyScore crossTraversalConsistency(const std::vector<std::int64_t>& representatives,
                                           const std::vector<int>& rooms,
                                           const std::vector<std::int64_t>& traversal_starts) {
  const int traversals = traversalCount(traversal_starts);
  ConsistencyScore score;
  const auto visits = roomVisits(rooms, traversal_starts, traversals);
  for (const auto& [room, per] : visits) {
    RoomConsistency rc;
    rc.room = room;
    rc.visits = per;
    rc.places.assign(static_cast<std::size_t>(traversals), 0);
    score.rooms.push_back(rc);
  }
  for (std::int64_t rep : representatives) {
    if (rep < 0 || rep >= static_cast<std::int64_t>(rooms.size())) continue;
    const int r = rooms[static_cast<std::size_t>(rep)];
    for (auto& rc : score.rooms) {
      if (rc.room == r) ++rc.places[static_cast<std::size_t>(traversalOf(rep, traversal_starts))];
    }
  }
  for (const auto& rc : score.rooms) {
    const bool visited_in_all = std::all_of(rc.visits.begin(), rc.visits.end(), [](int v) { return v > 0; });
    const bool any_place = std::any_of(rc.places.begin(), rc.places.end(), [](int v) { return v > 0; });
    if (!visited_in_all || !any_place) continue;
    ++score.eligible;
    if (std::all_of(rc.places.begin(), rc.places.end(), [](int v) { return v > 0; })) ++score.consistent;
  }
  score.rate = ratio(score.consistent, score.eligible);
  return score;
}

TopologyScore scoreTopology(const std::vector<int>& place_node, const std::vector<int>& place_room) {
  if (place_node.size() != place_room.size())
    throw std::invalid_argument("scoreTopology: place_node and place_room differ in length");
  TopologyScore score;
  std::map<int, std::set<int>> rooms_of_node;
  std::map<int, std::set<int>> nodes_of_room;
  std::set<int> nodes;
  std::map<int, std::set<int>> earlier_rooms_of_node;  // grows in detection order
  std::set<int> seen_nodes;
  std::set<int> seen_rooms_before_previous;
  for (std::size_t k = 0; k < place_node.size(); ++k) {
    const int n = place_node[k], r = place_room[k];
    nodes.insert(n);
    if (r >= 0) {
      rooms_of_node[n].insert(r);
      nodes_of_room[r].insert(n);
    }
    const bool known_node = seen_nodes.count(n) > 0;
    const bool stays = k > 0 && place_node[k - 1] == n;
    if (known_node && !stays) {
      ++score.loop_closures;
      const auto& earlier = earlier_rooms_of_node[n];
      if (r >= 0 && !earlier.empty() && earlier.count(r) == 0) ++score.wrong_loop_closures;
    }
    if (!known_node && r >= 0 && seen_rooms_before_previous.count(r) > 0) ++score.missed_loop_closures;
    if (k > 0 && place_room[k - 1] >= 0) seen_rooms_before_previous.insert(place_room[k - 1]);
    seen_nodes.insert(n);
    if (r >= 0) earlier_rooms_of_node[n].insert(r);
  }
  score.nodes = static_cast<int>(nodes.size());
  score.rooms = static_cast<int>(nodes_of_room.size());
  for (const auto& [n, rooms] : rooms_of_node) {
    if (rooms.size() >= 2) ++score.merged_nodes;
    if (rooms.size() == 1 && nodes_of_room[*rooms.begin()].size() == 1) ++score.one_to_one;
  }
  for (const auto& [r, ns] : nodes_of_room) {
    if (ns.size() >= 2) ++score.split_rooms;
  }
  return score;
}

namespace {

/// The counts of PlaceRevisitScore, with "frame f shows what frame g shows" and "f's truth is known" given.
template <typename Known, typename Same>
PlaceRevisitScore countPlaceRevisits(const std::vector<PlaceSpan>& places, std::int64_t frames, double min_overlap,
                                     const Known& known, const Same& same) {
  if (!(min_overlap > 0 && min_overlap <= 1))
    throw std::invalid_argument("scorePlaceRevisits: the overlap must be in (0, 1]");
  for (const PlaceSpan& p : places) {
    if (p.first < 0 || p.last < p.first || p.last >= frames)
      throw std::invalid_argument("scorePlaceRevisits: place frames " + std::to_string(p.first) + ".." +
                                  std::to_string(p.last) + " outside the " + std::to_string(frames) + " frames");
  }
  // Share of place k's known frames that place j covers.
  const auto overlap = [&](const PlaceSpan& k, const PlaceSpan& j) {
    int counted = 0, covered = 0;
    for (std::int64_t f = k.first; f <= k.last; ++f) {
      if (!known(f)) continue;
      ++counted;
      for (std::int64_t g = j.first; g <= j.last; ++g) {
        if (known(g) && same(f, g)) {
          ++covered;
          break;
        }
      }
    }
    return counted == 0 ? 0.0 : static_cast<double>(covered) / counted;
  };
  PlaceRevisitScore score;
  score.min_overlap = min_overlap;
  std::set<int> seen_nodes;
  for (std::size_t k = 0; k < places.size(); ++k) {
    const int node = places[k].node;
    if (node < 0) continue;
    ++score.places;
    std::set<int> revisited_nodes;
    bool revisits = false;
    for (std::size_t j = 0; j + 1 < k; ++j) {  // earlier places other than the previous one
      if (places[j].node < 0 || overlap(places[k], places[j]) < min_overlap) continue;
      revisits = true;
      revisited_nodes.insert(places[j].node);
    }
    const bool known_node = seen_nodes.count(node) > 0;
    const bool stays = k > 0 && places[k - 1].node == node;
    if (revisits) {
      ++score.revisits;
      if (revisited_nodes.count(node) > 0) {
        ++score.closed_right;
      } else if (!known_node) {
        ++score.missed;
      } else if (stays) {
        ++score.merged_with_previous;
      } else {
        ++score.wrong_closures;
      }
    } else if (known_node && !stays) {
      ++score.wrong_closures;
    }
    seen_nodes.insert(node);
  }
  return score;
}

}  // namespace

PlaceRevisitScore scorePlaceRevisits(const std::vector<PlaceSpan>& places, const std::vector<GroundPose>& poses,
                                     double radius_m, double max_heading_rad, double min_overlap) {
  if (!(radius_m > 0) || !(max_heading_rad > 0) || !(min_overlap > 0 && min_overlap <= 1))
    throw std::invalid_argument("scorePlaceRevisits: radius and heading must be > 0, overlap in (0, 1]");
  const auto known = [&](std::int64_t f) {
    const GroundPose& q = poses[static_cast<std::size_t>(f)];
    return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.heading);
  };
  const auto close = [&](std::int64_t f, std::int64_t g) {
    const GroundPose& a = poses[static_cast<std::size_t>(f)];
    const GroundPose& b = poses[static_cast<std::size_t>(g)];
    const double turn = std::abs(std::remainder(a.heading - b.heading, 2.0 * 3.14159265358979323846));
    return std::hypot(a.x - b.x, a.y - b.y) <= radius_m && turn <= max_heading_rad;
  };
  PlaceRevisitScore score =
      countPlaceRevisits(places, static_cast<std::int64_t>(poses.size()), min_overlap, known, close);
  score.radius_m = radius_m;
  score.max_heading_rad = max_heading_rad;
  return score;
}

FrameMatchPoseScore scoreFrameMatchesByPose(const std::vector<std::int64_t>& match, const std::vector<GroundPose>& poses,
                                            double radius_m, double max_heading_rad) {
  if (!(radius_m > 0) || !(max_heading_rad > 0))
    throw std::invalid_argument("scoreFrameMatchesByPose: radius and heading must be > 0");
  if (match.size() != poses.size())
    throw std::invalid_argument("scoreFrameMatchesByPose: " + std::to_string(match.size()) + " frames but " +
                                std::to_string(poses.size()) + " poses");
  const auto known = [](const GroundPose& q) { return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.heading); };
  FrameMatchPoseScore score;
  score.radius_m = radius_m;
  score.max_heading_rad = max_heading_rad;
  for (std::size_t f = 0; f < match.size(); ++f) {
    const std::int64_t g = match[f];
    if (g < 0 || g >= static_cast<std::int64_t>(poses.size())) continue;
    const GroundPose& a = poses[f];
    const GroundPose& b = poses[static_cast<std::size_t>(g)];
    if (!known(a) || !known(b)) continue;
    ++score.matches;
    const double turn = std::abs(std::remainder(a.heading - b.heading, 2.0 * 3.14159265358979323846));
    if (std::hypot(a.x - b.x, a.y - b.y) <= radius_m && turn <= max_heading_rad) ++score.right;
    else ++score.wrong;
  }
  return score;
}

PlaceRevisitScore scorePlaceRevisits(const std::vector<PlaceSpan>& places, const LoopClosureMatrix& same,
                                     double min_overlap) {
  // A frame with no true match anywhere still counts: a place of frames nobody saw again covers nothing.
  const auto known = [](std::int64_t) { return true; };
  const auto shows = [&](std::int64_t f, std::int64_t g) { return same.at(static_cast<int>(f), static_cast<int>(g)); };
  PlaceRevisitScore score = countPlaceRevisits(places, same.size, min_overlap, known, shows);
  score.by_pose = false;
  return score;
}

PlaceRevisitScore scorePlaceRevisits(const std::vector<PlaceSpan>& places, const std::vector<int>& rooms,
                                     double min_overlap) {
  const auto known = [](std::int64_t) { return true; };
  const auto room = [&](std::int64_t f) { return rooms[static_cast<std::size_t>(f)]; };
  const auto shows = [&](std::int64_t f, std::int64_t g) { return room(f) >= 0 && room(f) == room(g); };
  PlaceRevisitScore score =
      countPlaceRevisits(places, static_cast<std::int64_t>(rooms.size()), min_overlap, known, shows);
  score.by_pose = false;
  score.by_rooms = true;
  return score;
}

int majority(const std::vector<int>& values) {
  std::map<int, int> counts;
  for (int v : values) {
    if (v >= 0) ++counts[v];
  }
  int best = -1, best_count = 0;
  for (const auto& [v, c] : counts) {
    if (c > best_count) {
      best = v;
      best_count = c;
    }
  }
  return best;
}

}  // namespace toposlam::eval
