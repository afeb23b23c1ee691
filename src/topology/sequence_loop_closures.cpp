// Frame-level loop closures by sequence evidence: see sequence_loop_closures.hpp.
#include "toposlam/topology/sequence_loop_closures.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <stdexcept>

namespace toposlam {

namespace {

/// A keyframe: the first frame, one whose clock went back (a new traversal), or one at least an interval
/// after the last keyframe.
bool isKeyframe(bool first, double time_s, double last_keyframe_time_s, double interval_s) {
  return first || time_s < last_keyframe_time_s || time_s - last_keyframe_time_s >= interval_s * (1.0 - 1e-9);
}

}  // namespace

std::string SequenceLoopConfig::validate() const {
  if (!(keyframe_interval_s >= 0.0) || !std::isfinite(keyframe_interval_s))
    return "keyframe interval must be a finite number of seconds >= 0 (got " + std::to_string(keyframe_interval_s) + ")";
  if (!(decay >= 0.0 && decay < 1.0)) return "loop decay must be in [0, 1) (got " + std::to_string(decay) + ")";
  if (scales < 1 || scales > 8) return "loop scales must be 1 .. 8 (got " + std::to_string(scales) + ")";
  if (!(scale_ratio >= 1.0 && scale_ratio <= 100.0))
    return "loop scale ratio must be in [1, 100] (got " + std::to_string(scale_ratio) + ")";
  if (align_keyframes < 0 || align_keyframes > 1000)
    return "loop alignment must be 0 .. 1000 keyframes (got " + std::to_string(align_keyframes) + ")";
  if (min_gap_keyframes < 1) return "loop minimum gap must be at least 1 keyframe (got " + std::to_string(min_gap_keyframes) + ")";
  if (!(sigma_floor > 0.0) || !std::isfinite(sigma_floor))
    return "loop sigma floor must be > 0 (got " + std::to_string(sigma_floor) + ")";
  return {};
}

double SequenceLoopConfig::decayOf(int k) const {
  return std::max(0.0, 1.0 - (1.0 - decay) * std::pow(scale_ratio, k));
}

SequenceLoopDetector::SequenceLoopDetector(SequenceLoopConfig config) : config_(config) {
  if (const std::string problem = config_.validate(); !problem.empty())
    throw std::invalid_argument("SequenceLoopDetector: " + problem);
  integrated_.resize(static_cast<std::size_t>(config_.scales));
}

SequenceLoopDetector::Detection SequenceLoopDetector::add(const std::vector<double>& similarities,
                                                          bool continues_previous) {
  const std::size_t n = starts_run_.size();  // earlier keyframes
  if (similarities.size() != n)
    throw std::invalid_argument("SequenceLoopDetector::add: " + std::to_string(similarities.size()) +
                                " similarities for " + std::to_string(n) + " earlier keyframes");
  // Relative similarity: how far each earlier keyframe stands out of all of them (sums in index order).
  double mean = 0.0;
  for (const double s : similarities) mean += s;
  double sigma = 0.0;
  if (n > 0) {
    mean /= static_cast<double>(n);
    for (const double s : similarities) sigma += (s - mean) * (s - mean);
    sigma = std::sqrt(sigma / static_cast<double>(n));
  }
  const double spread = std::max(sigma, config_.sigma_floor);
  z_.assign(n, 0.0);
  if (n >= 2)
    for (std::size_t g = 0; g < n; ++g) z_[g] = (similarities[g] - mean) / spread;
  return integrate(similarities, continues_previous);
}

SequenceLoopDetector::Detection SequenceLoopDetector::addSparse(const std::vector<double>& similarities, double mean,
                                                                double spread, bool continues_previous) {
  const std::size_t n = starts_run_.size();
  if (similarities.size() != n)
    throw std::invalid_argument("SequenceLoopDetector::addSparse: " + std::to_string(similarities.size()) +
                                " similarities for " + std::to_string(n) + " earlier keyframes");
  spread = std::max(spread, config_.sigma_floor);
  z_.assign(n, 0.0);
  if (n >= 2)
    for (std::size_t g = 0; g < n; ++g)
      if (!std::isnan(similarities[g])) z_[g] = (similarities[g] - mean) / spread;
  return integrate(similarities, continues_previous);
}

std::vector<std::size_t> SequenceLoopDetector::continuations(std::size_t per_memory) const {
  std::vector<std::size_t> out;
  std::vector<std::pair<double, std::size_t>> live;
  for (const std::vector<double>& integrated : integrated_) {
    live.clear();
    // integrated holds D(latest, g) for g < latest and the latest keyframe's own slot (0).
    for (std::size_t g = 0; g + 1 < integrated.size(); ++g)
      if (integrated[g] > 0.0) live.emplace_back(integrated[g], g);
    const std::size_t keep = std::min(per_memory, live.size());
    std::partial_sort(live.begin(), live.begin() + static_cast<std::ptrdiff_t>(keep), live.end(),
                      [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
    for (std::size_t i = 0; i < keep; ++i)
      for (std::size_t g = live[i].second; g <= live[i].second + 2; ++g) out.push_back(g);  // (g + 1) +- 1
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  const std::size_t n = starts_run_.size();  // the next keyframe's earlier keyframes: 0 .. n - 1
  while (!out.empty() && out.back() >= n) out.pop_back();
  return out;
}

SequenceLoopDetector::Detection SequenceLoopDetector::integrate(const std::vector<double>& similarities,
                                                                bool continues_previous) {
  const std::size_t n = starts_run_.size();
  // Per memory k: D_k(f, g) = (1 - d_k) z_g + d_k D_k(f-1, g-1), carried only where both f-1 -> f and
  // g-1 -> g are steps of one traversal (g = 0 and the first keyframe of a traversal start a diagonal).
  Detection best;
  const auto gap = static_cast<std::size_t>(config_.min_gap_keyframes);
  score_.assign(n, 0.0);
  for (std::size_t k = 0; k < integrated_.size(); ++k) {
    const double d = config_.decayOf(static_cast<int>(k));
    const double noise = std::sqrt((1.0 - d) / (1.0 + d));
    std::vector<double>& integrated = integrated_[k];
    if (next_.capacity() < n + 1) next_.reserve(2 * (n + 1));  // the buffers swap: grow geometrically
    next_.assign(n + 1, 0.0);  // one more slot: the new keyframe's own entry for the next call
    for (std::size_t g = 0; g < n; ++g) {
      const double carried = continues_previous && g >= 1 && !starts_run_[g] ? integrated[g - 1] : 0.0;
      next_[g] = (1.0 - d) * z_[g] + d * carried;
    }
    if (n >= gap) {
      for (std::size_t g = 0; g + gap <= n; ++g) {
        const double score = next_[g] / noise;
        if (next_[g] > 0.0) score_[g] = std::max(score_[g], score);
        if (next_[g] > 0.0 && (best.diagonal < 0 || score > best.score)) {
          best.diagonal = static_cast<std::int64_t>(g);
          best.score = score;
        }
      }
    }
    integrated.swap(next_);
  }

  if (best.diagonal >= 0) {
    // Alignment: the most similar keyframe around the diagonal's end (first of equals), never too recent.
    const auto end = static_cast<std::size_t>(best.diagonal);
    const auto align = static_cast<std::size_t>(config_.align_keyframes);
    const std::size_t lo = end >= align ? end - align : 0;
    const std::size_t hi = std::min(end + align, n - gap);
    std::size_t at = end;
    for (std::size_t g = lo; g <= hi; ++g)
      if (!std::isnan(similarities[g]) && (std::isnan(similarities[at]) || similarities[g] > similarities[at])) at = g;
    best.keyframe = static_cast<std::int64_t>(at);
    best.relative = z_[end];  // the diagonal's own (the best of a few neighbours would stand out by chance)
    // The runner-up: the best run ending away from this one and from every keyframe of its place.
    const std::int64_t distinct = config_.distinct_keyframes;
    const auto own = static_cast<std::int64_t>(end);
    for (std::size_t g = 0; g + gap <= n; ++g) {
      const auto other = static_cast<std::int64_t>(g);
      if (std::abs(other - own) > distinct && std::abs(place_[g] - place_[end]) > distinct)
        best.runner_up = std::max(best.runner_up, score_[g]);
    }
  }
  starts_run_.push_back(n == 0 || !continues_previous);
  place_.push_back(static_cast<std::int64_t>(n));
  return best;
}

void SequenceLoopDetector::link(std::int64_t earlier) {
  if (place_.empty() || earlier < 0 || earlier + 1 >= static_cast<std::int64_t>(place_.size()))
    throw std::invalid_argument("SequenceLoopDetector::link: keyframe " + std::to_string(earlier) +
                                " is not earlier than the latest");
  place_.back() = place_[static_cast<std::size_t>(earlier)];
}

SequenceLoopConfig SequenceEvidenceConfig::loopConfig() const {
  SequenceLoopConfig c = loop;
  c.decay = 1.0 - loop.keyframe_interval_s / memory_s;
  c.min_gap_keyframes = static_cast<int>(std::ceil(min_gap_s / loop.keyframe_interval_s - 1e-9));
  c.distinct_keyframes = static_cast<int>(std::ceil(distinct_s / loop.keyframe_interval_s - 1e-9));
  return c;
}

std::string SequenceEvidenceConfig::validate() const {
  if (!(loop.keyframe_interval_s > 0.0) || !std::isfinite(loop.keyframe_interval_s))
    return "keyframe interval must be a finite number of seconds > 0 (got " + std::to_string(loop.keyframe_interval_s) + ")";
  if (!(memory_s > loop.keyframe_interval_s) || !std::isfinite(memory_s))
    return "sequence memory must be longer than the keyframe interval (got " + std::to_string(memory_s) + " s)";
  if (!(min_gap_s >= loop.keyframe_interval_s) || !std::isfinite(min_gap_s) || min_gap_s / loop.keyframe_interval_s > 1e6)
    return "sequence minimum gap must be at least one keyframe interval and at most a million of them (got " +
           std::to_string(min_gap_s) + " s)";
  if (std::string problem = loopConfig().validate(); !problem.empty()) return problem;
  if (!(min_score >= 0.0) || !std::isfinite(min_score))
    return "sequence evidence minimum score must be a finite number >= 0 (got " + std::to_string(min_score) + ")";
  if (!std::isfinite(min_relative))
    return "sequence evidence minimum relative similarity must be finite (got " + std::to_string(min_relative) + ")";
  if (!(min_share >= 0.0 && min_share <= 1.0))
    return "sequence evidence minimum share must be in [0, 1] (got " + std::to_string(min_share) + ")";
  if (!(weight >= 0.0 && weight <= 1.0)) return "sequence evidence weight must be in [0, 1] (got " + std::to_string(weight) + ")";
  if (exhaustive_up_to < 0) return "sequence exhaustive_up_to must be >= 0 keyframes (got " + std::to_string(exhaustive_up_to) + ")";
  if (candidates < 1 || candidates > 10000) return "sequence candidates must be 1 .. 10000 (got " + std::to_string(candidates) + ")";
  if (diagonals < 1 || diagonals > 10000) return "sequence diagonals must be 1 .. 10000 (got " + std::to_string(diagonals) + ")";
  if (statistics_sample < 2 || statistics_sample > 100000)
    return "sequence statistics_sample must be 2 .. 100000 (got " + std::to_string(statistics_sample) + ")";
  return {};
}

namespace {

const SequenceEvidenceConfig& validated(const SequenceEvidenceConfig& config) {
  if (const std::string problem = config.validate(); !problem.empty())
    throw std::invalid_argument("PlaceSequenceEvidence: " + problem);
  return config;
}

}  // namespace

PlaceSequenceEvidence::PlaceSequenceEvidence(const SequenceEvidenceConfig& config, const SimilarityMeasure& similarity)
    : config_(validated(config)), similarity_(similarity), detector_(config_.loopConfig()) {}

FrameRevisit PlaceSequenceEvidence::addFrame(std::int64_t frame, double time_s,
                                             const std::shared_ptr<const Fingerprint>& fingerprint) {
  if (!fingerprint || !std::isfinite(time_s)) return {};
  if (!keyframe_frames_.empty() && frame <= keyframe_frames_.back())
    throw std::invalid_argument("PlaceSequenceEvidence::addFrame: frame " + std::to_string(frame) +
                                " after frame " + std::to_string(keyframe_frames_.back()));
  const bool first = keyframe_frames_.empty();
  if (!isKeyframe(first || traversal_break_, time_s, last_keyframe_time_s_, config_.loop.keyframe_interval_s)) {
    // Between keyframes: the keyframe's match, moved on by as many frames as this one lies after it.
    const std::int64_t keyframe = keyframe_frames_.back();  // not first: there is one
    FrameRevisit shifted = last_keyframe_revisit_;
    if (shifted.match_frame >= 0) shifted.match_frame += frame - keyframe;
    if (shifted.match_frame >= keyframe) shifted = FrameRevisit{};
    return shifted;
  }
  const bool continues = !first && !traversal_break_ && time_s >= last_keyframe_time_s_;
  const std::size_t n = keyframe_fingerprints_.size();
  const bool indexed = PlaceCandidateIndex::supports(*fingerprint);
  SequenceLoopDetector::Detection d;
  if (!indexed || index_ == nullptr || n <= static_cast<std::size_t>(config_.exhaustive_up_to)) {
    row_.clear();
    for (const auto& earlier : keyframe_fingerprints_)
      row_.push_back(std::clamp(similarity_.symmetricSimilarity(*earlier, *fingerprint), 0.0, 1.0));
    compared_ += static_cast<std::int64_t>(n);
    d = detector_.add(row_, continues);
  } else {
    double mean = 0.0, spread = 0.0;
    compareSparse(*fingerprint, mean, spread);
    d = detector_.addSparse(row_, mean, spread, continues);
  }
  // The index is built when it is first needed, from every keyframe so far, then kept up to date: a run
  // that stays below exhaustive_up_to keyframes never pays its memory (tables of buckets, an entry per
  // descriptor and table).
  if (index_ == nullptr && n + 1 > static_cast<std::size_t>(config_.exhaustive_up_to)) {
    index_ = std::make_unique<PlaceCandidateIndex>();
    for (std::size_t g = 0; g < n; ++g)
      if (PlaceCandidateIndex::supports(*keyframe_fingerprints_[g])) index_->add(static_cast<int>(g), *keyframe_fingerprints_[g]);
  }
  if (indexed && index_ != nullptr) index_->add(static_cast<int>(n), *fingerprint);
  KeyframeDetection record{frame, -1};
  FrameRevisit revisit;
  if (d.keyframe >= 0 && d.score >= config_.min_score && d.score - d.runner_up >= config_.min_margin &&
      d.relative >= config_.min_relative) {
    record.matched_frame = keyframe_frames_[static_cast<std::size_t>(d.keyframe)];
    revisit = FrameRevisit{record.matched_frame, d.score};
    detector_.link(d.keyframe);
  }
  open_detections_.push_back(record);
  keyframe_fingerprints_.push_back(fingerprint);
  keyframe_frames_.push_back(frame);
  last_keyframe_time_s_ = time_s;
  traversal_break_ = false;
  last_keyframe_revisit_ = revisit;
  return revisit;
}

void PlaceSequenceEvidence::compareSparse(const Fingerprint& fingerprint, double& mean, double& spread) {
  const std::size_t n = keyframe_fingerprints_.size();
  row_.assign(n, std::numeric_limits<double>::quiet_NaN());
  const auto compare = [&](std::size_t g) {
    if (g >= n || !std::isnan(row_[g])) return;
    row_[g] = std::clamp(similarity_.symmetricSimilarity(*keyframe_fingerprints_[g], fingerprint), 0.0, 1.0);
    ++compared_;
  };
  // The relative similarity's mean and spread from keyframes spread evenly over the whole history (the
  // candidates below are the most similar ones: they would bias both).
  const std::size_t m = std::min(n, static_cast<std::size_t>(config_.statistics_sample));
  double sum = 0.0, squares = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    const std::size_t g = (i * n + n / 2) / m;  // evenly spaced, the same for every keyframe of a size
    compare(g);
    sum += row_[g];
    squares += row_[g] * row_[g];
  }
  mean = m > 0 ? sum / static_cast<double>(m) : 0.0;
  spread = m > 0 ? std::sqrt(std::max(0.0, squares / static_cast<double>(m) - mean * mean)) : 0.0;
  // Where the robot may be back: the index's candidates (and their neighbours, for the alignment), and
  // every live diagonal's next step.
  for (const int g : index_->candidates(fingerprint, config_.candidates)) {
    const auto at = static_cast<std::size_t>(g);
    for (std::size_t a = at > 0 ? at - 1 : 0; a <= at + 1; ++a) compare(a);
  }
  for (const std::size_t g : detector_.continuations(static_cast<std::size_t>(config_.diagonals))) compare(g);
}

std::int64_t PlaceSequenceEvidence::placeOfFrame(std::int64_t frame) const {
  // The last place starting at or before `frame`, if it reaches it.
  const auto it = std::upper_bound(places_.begin(), places_.end(), frame,
                                   [](std::int64_t f, const std::pair<std::int64_t, std::int64_t>& p) { return f < p.first; });
  if (it == places_.begin()) return -1;
  const auto& place = *std::prev(it);
  return frame <= place.second ? static_cast<std::int64_t>(std::prev(it) - places_.begin()) : -1;
}

std::vector<double> PlaceSequenceEvidence::closePlace(std::int64_t first_frame, std::int64_t last_frame) {
  if (last_frame < first_frame)
    throw std::invalid_argument("PlaceSequenceEvidence::closePlace: last frame before the first");
  if (!places_.empty() && first_frame <= places_.back().second)
    throw std::invalid_argument("PlaceSequenceEvidence::closePlace: place from frame " + std::to_string(first_frame) +
                                " overlaps the previous one (to frame " + std::to_string(places_.back().second) + ")");
  std::vector<double> evidence(places_.size(), 0.0);
  int keyframes_in_place = 0;
  std::vector<KeyframeDetection> still_open;
  for (const KeyframeDetection& k : open_detections_) {
    if (k.frame > last_frame) {
      still_open.push_back(k);
      continue;
    }
    if (k.frame < first_frame) continue;  // a dropped place's keyframe
    ++keyframes_in_place;
    if (k.matched_frame < 0) continue;
    const std::int64_t place = placeOfFrame(k.matched_frame);
    if (place >= 0) evidence[static_cast<std::size_t>(place)] += 1.0;
  }
  open_detections_.swap(still_open);
  if (keyframes_in_place > 0)
    for (double& e : evidence) {
      const double share = e / keyframes_in_place;
      e = share >= config_.min_share ? config_.weight * share : 0.0;
    }
  places_.emplace_back(first_frame, last_frame);
  return evidence;
}

}  // namespace toposlam
