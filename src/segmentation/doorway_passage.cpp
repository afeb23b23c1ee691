// DoorwayPassageDetector: outward edge tracks, their time to contact, left/right pairs. See the header.
#include "toposlam/segmentation/doorway_passage.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace toposlam {

std::string DoorwayPassageConfig::validate() const {
  std::ostringstream problem;
  if (min_track_frames < 2 || min_track_frames > DoorwayPassageDetector::kFitPoints) {
    problem << "min_track_frames: " << min_track_frames << " is outside the allowed range [2, "
            << DoorwayPassageDetector::kFitPoints << "]";
  } else if (!(fit_s > 0.0 && fit_s <= 10.0)) {
    problem << "fit_s: " << fit_s << " is outside the allowed range (0, 10]";
  } else if (!(border_fraction > 0.0 && border_fraction <= 1.0)) {
    problem << "border_fraction: " << border_fraction << " is outside the allowed range (0, 1]";
  } else if (!(max_growth >= 1.0 && max_growth <= 10.0)) {
    problem << "max_growth: " << max_growth << " is outside the allowed range [1, 10]";
  } else if (!(step_fraction >= 0.0 && step_fraction <= 1.0)) {
    problem << "step_fraction: " << step_fraction << " is outside the allowed range [0, 1]";
  } else if (!(min_outward_speed_fraction >= 0.0 && min_outward_speed_fraction <= 1.0)) {
    problem << "min_outward_speed_fraction: " << min_outward_speed_fraction << " is outside the allowed range [0, 1]";
  } else if (!(max_lookahead_s > 0.0 && max_lookahead_s <= 60.0)) {
    problem << "max_lookahead_s: " << max_lookahead_s << " is outside the allowed range (0, 60]";
  } else if (!(pair_tolerance_s >= 0.0 && pair_tolerance_s <= 10.0)) {
    problem << "pair_tolerance_s: " << pair_tolerance_s << " is outside the allowed range [0, 10]";
  } else if (!(pair_tolerance_fraction >= 0.0 && pair_tolerance_fraction <= 1.0)) {
    problem << "pair_tolerance_fraction: " << pair_tolerance_fraction << " is outside the allowed range [0, 1]";
  } else if (!(max_exit_gap_s >= 0.0 && max_exit_gap_s <= 10.0)) {
    problem << "max_exit_gap_s: " << max_exit_gap_s << " is outside the allowed range [0, 10]";
  } else if (!(max_frame_gap_s > 0.0 && max_frame_gap_s <= 60.0)) {
    problem << "max_frame_gap_s: " << max_frame_gap_s << " is outside the allowed range (0, 60]";
  }
  return problem.str();
}

DoorwayPassageDetector::DoorwayPassageDetector(const DoorwayPassageConfig& config) : config_(config) {
  if (const std::string problem = config_.validate(); !problem.empty()) {
    throw std::invalid_argument("doorway passage config: " + problem);
  }
  tracks_.reserve(kMaxTracks);
  next_tracks_.reserve(kMaxTracks);
  edge_used_.reserve(kMaxEdges);
  exits_.reserve(kMaxExits);
  passages_.reserve(kMaxPassages);
}

void DoorwayPassageDetector::addFrame(double time_s, int image_width, const std::vector<int>& edge_columns) {
  if (started_ && !(time_s > last_time_s_)) {
    // A new traversal (or a repeated time): nothing carries over from the frames before.
    tracks_.clear();
    exits_.clear();
    passages_.clear();
    frame_interval_s_ = 0.0;
  }
  if (started_ && time_s - last_time_s_ > config_.max_frame_gap_s) {
    // A gap (the robot stood, frames were left out): no track or pending track end carries over, and a
    // passage predicted beyond the last frame before it assumed the robot kept going.
    tracks_.clear();
    exits_.clear();
    std::erase_if(passages_, [&](double passage_s) { return passage_s > last_time_s_; });
  } else if (started_ && time_s > last_time_s_) {
    frame_interval_s_ = time_s - last_time_s_;
  }
  started_ = true;
  last_time_s_ = time_s;
  if (image_width <= 0) return;
  const double half = 0.5 * static_cast<double>(image_width);
  const std::size_t edges = std::min<std::size_t>(edge_columns.size(), kMaxEdges);
  edge_used_.assign(edges, 0);
  const auto offsetOf = [&](std::size_t j) { return std::max(1.0, std::abs(edge_columns[j] - half)); };
  const auto sideOf = [&](std::size_t j) { return edge_columns[j] < half ? -1 : 1; };

  // Outermost tracks first, so each claims its own continuation before an inner one can.
  std::sort(tracks_.begin(), tracks_.end(),
            [](const Track& a, const Track& b) { return a.lastOffset() > b.lastOffset(); });
  const double step = config_.step_fraction * half;
  next_tracks_.clear();
  for (const Track& track : tracks_) {
    const double last = track.lastOffset();
    const double min_growth = minContinuationGrowth(track, time_s, step);
    std::size_t best = edges;
    double best_growth = 0.0;
    for (std::size_t j = 0; j < edges; ++j) {
      if (edge_used_[j] != 0 || sideOf(j) != track.side) continue;
      const double growth = offsetOf(j) - last;
      if (growth < min_growth || offsetOf(j) > last * config_.max_growth + step) continue;
      if (best == edges || growth < best_growth) {
        best = j;
        best_growth = growth;
      }
    }
    if (best == edges) {
      endTrack(track, half);
      continue;
    }
    edge_used_[best] = 1;
    Track next = track;
    const auto at = static_cast<std::size_t>(next.count % kFitPoints);
    next.time[at] = time_s;
    next.offset[at] = offsetOf(best);
    ++next.count;
    next_tracks_.push_back(next);
  }
  // Edges no track took start tracks of their own (not at the border already: they could only leave).
  for (std::size_t j = 0; j < edges && next_tracks_.size() < static_cast<std::size_t>(kMaxTracks); ++j) {
    if (edge_used_[j] != 0 || offsetOf(j) >= config_.border_fraction * half) continue;
    Track track;
    track.time[0] = time_s;
    track.offset[0] = offsetOf(j);
    track.count = 1;
    track.side = sideOf(j);
    track.first_offset = offsetOf(j);
    next_tracks_.push_back(track);
  }
  tracks_.swap(next_tracks_);
  // Track ends older than any partner could still be are forgotten.
  std::erase_if(exits_, [&](const Exit& e) { return e.last_s < time_s - 2.0 * config_.max_lookahead_s; });
}

int DoorwayPassageDetector::recentPoints(const Track& track, int at_least) const {
  const int kept = std::min(track.count, kFitPoints);
  int n = 0;
  while (n < kept && (n < at_least || track.time[static_cast<std::size_t>((track.count - 1 - n) % kFitPoints)] >=
                                          track.lastTime() - config_.fit_s - 1e-9)) {
    ++n;
  }
  return n;
}

double DoorwayPassageDetector::minContinuationGrowth(const Track& track, double time_s, double step) const {
  // An edge that has been moving out keeps moving out: a continuation must move out by at least
  // min_outward_speed_fraction of the track's mean outward speed over its last fit_s seconds, less the
  // inward jitter. A stalled edge where a fast one was expected is another edge (the jamb left the view
  // and a far edge at the border took its place).
  const double jitter = 0.25 * step;
  if (!(config_.min_outward_speed_fraction > 0.0)) return -jitter;
  const int n = recentPoints(track, 1);
  if (n < 2) return -jitter;
  const auto first = static_cast<std::size_t>((track.count - n) % kFitPoints);
  const double span_s = track.lastTime() - track.time[first];
  const double speed = span_s > 0.0 ? (track.lastOffset() - track.offset[first]) / span_s : 0.0;
  if (!(speed > 0.0)) return -jitter;
  return std::max(-jitter, config_.min_outward_speed_fraction * speed * (time_s - track.lastTime()) - jitter);
}

void DoorwayPassageDetector::endTrack(const Track& track, double half_width) {
  if (track.count < config_.min_track_frames) return;
  if (track.lastOffset() < config_.border_fraction * half_width) return;
  // Least-squares line through (t, 1/|x|) over the track's last points, t relative to its last frame.
  const double last_s = track.lastTime();
  const int n = recentPoints(track, config_.min_track_frames);
  double st = 0.0, sy = 0.0;
  for (int k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>((track.count - 1 - k) % kFitPoints);
    st += track.time[i] - last_s;
    sy += 1.0 / track.offset[i];
  }
  const double mean_t = st / n, mean_y = sy / n;
  double sxx = 0.0, sxy = 0.0;
  for (int k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>((track.count - 1 - k) % kFitPoints);
    const double dt = track.time[i] - last_s - mean_t;
    sxx += dt * dt;
    sxy += dt * (1.0 / track.offset[i] - mean_y);
  }
  if (!(sxx > 0.0)) return;
  const double slope = sxy / sxx;
  // The edge must have moved out (an edge standing at the border, seen while turning, is no doorway).
  if (!(slope < 0.0) || track.lastOffset() < 1.15 * track.first_offset) return;
  const double to_go_s = (slope * mean_t - mean_y) / slope;  // where the line reaches 0, after last_s
  if (!(to_go_s > -0.5 * config_.max_lookahead_s && to_go_s <= config_.max_lookahead_s)) return;
  const Exit exit{last_s + std::max(0.0, to_go_s), last_s, track.side};
  for (const Exit& other : exits_) {
    if (other.side == exit.side || std::abs(other.last_s - exit.last_s) > config_.max_exit_gap_s) continue;
    const double still_to_go = std::max(0.0, std::min(exit.passage_s, other.passage_s) - std::max(exit.last_s, other.last_s));
    // Two frame intervals at least: at 2 fps a track is three frames a second apart, and so is its fit.
    const double tolerance = std::max({config_.pair_tolerance_s, 2.0 * frame_interval_s_,
                                       config_.pair_tolerance_fraction * still_to_go});
    if (std::abs(other.passage_s - exit.passage_s) <= tolerance) {
      recordPassage(0.5 * (other.passage_s + exit.passage_s));
      break;
    }
  }
  if (exits_.size() == static_cast<std::size_t>(kMaxExits)) exits_.erase(exits_.begin());
  exits_.push_back(exit);
}

void DoorwayPassageDetector::recordPassage(double passage_s) {
  // Both jambs have two edges (inner and outer face): their pairs describe the same passage.
  for (const double known : passages_) {
    if (std::abs(known - passage_s) <= config_.pair_tolerance_s) return;
  }
  if (passages_.size() == static_cast<std::size_t>(kMaxPassages)) passages_.erase(passages_.begin());
  passages_.insert(std::upper_bound(passages_.begin(), passages_.end(), passage_s), passage_s);
  ++passage_count_;
}

std::optional<double> DoorwayPassageDetector::firstPassageAfter(double after_s) const {
  const auto it = std::upper_bound(passages_.begin(), passages_.end(), after_s);
  if (it == passages_.end()) return std::nullopt;
  return *it;
}

std::optional<double> DoorwayPassageDetector::nearestPassage(double time_s, double max_distance_s) const {
  std::optional<double> best;
  for (const double passage : passages_) {
    const double distance = std::abs(passage - time_s);
    if (distance > max_distance_s) continue;
    if (!best || distance < std::abs(*best - time_s)) best = passage;
  }
  return best;
}

}  // namespace toposlam
