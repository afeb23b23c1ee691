// Frame-level loop closures by sequence evidence: see sequence_loop_closures.hpp.
#include "toposlam/topology/sequence_loop_closures.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
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
  if (min_gap_keyframes < 1) return "loop minimum gap must be at least 1 keyframe (got " + std::to_string(min_gap_keyframes) + ")";
  if (!(sigma_floor > 0.0) || !std::isfinite(sigma_floor))
    return "loop sigma floor must be > 0 (got " + std::to_string(sigma_floor) + ")";
  return {};
}

SequenceLoopDetector::SequenceLoopDetector(SequenceLoopConfig config) : config_(config) {
  if (const std::string problem = config_.validate(); !problem.empty())
    throw std::invalid_argument("SequenceLoopDetector: " + problem);
}

SequenceLoopDetector::Detection SequenceLoopDetector::add(const std::vector<double>& similarities,
                                                          bool continues_previous) {
  const std::size_t n = integrated_.size();  // earlier keyframes
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
  // D(f, g) = (1 - decay) z_g + decay D(f-1, g-1), carried only where both f-1 -> f and g-1 -> g are
  // steps of one traversal (g = 0 and the first keyframe of a traversal start a diagonal).
  if (next_.capacity() < n + 1) next_.reserve(2 * (n + 1));  // the two buffers swap: grow both geometrically
  next_.assign(n + 1, 0.0);  // one more slot: the new keyframe's own entry for the next call
  for (std::size_t g = 0; g < n; ++g) {
    const double z = n >= 2 ? (similarities[g] - mean) / spread : 0.0;
    const double carried = continues_previous && g >= 1 && !starts_run_[g] ? integrated_[g - 1] : 0.0;
    next_[g] = (1.0 - config_.decay) * z + config_.decay * carried;
  }
  Detection best;
  const auto gap = static_cast<std::size_t>(config_.min_gap_keyframes);
  if (n >= gap) {
    for (std::size_t g = 0; g + gap <= n; ++g) {
      if (next_[g] > 0.0 && (best.keyframe < 0 || next_[g] > best.score)) {
        best.keyframe = static_cast<std::int64_t>(g);
        best.score = next_[g];
        best.relative = n >= 2 ? (similarities[g] - mean) / spread : 0.0;
      }
    }
  }
  integrated_.swap(next_);
  starts_run_.push_back(n == 0 || !continues_previous);
  return best;
}

std::vector<FrameMatch> matchFramesBySequence(const std::vector<double>& time_s,
                                              const std::vector<std::shared_ptr<const Fingerprint>>& fingerprints,
                                              const SimilarityMeasure& similarity, const SequenceLoopConfig& config) {
  if (time_s.size() != fingerprints.size()) throw std::invalid_argument("matchFramesBySequence: sizes differ");
  SequenceLoopDetector detector(config);
  const auto frames = static_cast<std::int64_t>(fingerprints.size());
  std::vector<FrameMatch> out(fingerprints.size());
  std::vector<std::int64_t> keyframe_frames;  // frame index of each keyframe
  std::vector<double> row;
  // The most similar frame with a fingerprint in [centre - half, centre + half], before `before`.
  const auto refine = [&](std::int64_t f, std::int64_t centre, std::int64_t half, std::int64_t before, FrameMatch& m) {
    for (std::int64_t c = std::max<std::int64_t>(0, centre - half); c <= std::min(centre + half, before - 1); ++c) {
      const auto& candidate = fingerprints[static_cast<std::size_t>(c)];
      if (!candidate) continue;
      const double s = similarity.symmetricSimilarity(*candidate, *fingerprints[static_cast<std::size_t>(f)]);
      if (m.match_frame < 0 || s > m.similarity) {
        m.match_frame = c;
        m.similarity = s;
      }
    }
  };
  std::int64_t last_key = -1;          // frame index of the latest keyframe
  std::int64_t last_key_match = -1;    // its detected frame (-1: none)
  std::int64_t half_spacing = 0;       // half the frames between the last two keyframes
  double last_key_score = 0.0;
  for (std::int64_t f = 0; f < frames; ++f) {
    const auto& fp = fingerprints[static_cast<std::size_t>(f)];
    if (!fp) continue;
    const double t = time_s[static_cast<std::size_t>(f)];
    const bool keyframe =
        isKeyframe(last_key < 0, t, last_key < 0 ? 0.0 : time_s[static_cast<std::size_t>(last_key)], config.keyframe_interval_s);
    if (keyframe) {
      row.clear();
      for (const std::int64_t k : keyframe_frames)
        row.push_back(std::clamp(similarity.symmetricSimilarity(*fingerprints[static_cast<std::size_t>(k)], *fp), 0.0, 1.0));
      // A clock that goes back starts a new traversal: no diagonal runs across it.
      const bool continues = last_key >= 0 && t >= time_s[static_cast<std::size_t>(last_key)];
      const SequenceLoopDetector::Detection d = detector.add(row, continues);
      half_spacing = last_key < 0 ? 0 : (f - last_key) / 2;
      keyframe_frames.push_back(f);
      last_key = f;
      last_key_match = d.keyframe >= 0 ? keyframe_frames[static_cast<std::size_t>(d.keyframe)] : -1;
      last_key_score = d.score;
    }
    if (last_key_match < 0) continue;
    FrameMatch& m = out[static_cast<std::size_t>(f)];
    refine(f, last_key_match + (f - last_key), half_spacing, f, m);
    if (m.match_frame >= 0) m.score = last_key_score;
  }
  return out;
}

std::string SequenceEvidenceConfig::validate() const {
  if (std::string problem = loop.validate(); !problem.empty()) return problem;
  if (!(min_score >= 0.0) || !std::isfinite(min_score))
    return "sequence evidence minimum score must be a finite number >= 0 (got " + std::to_string(min_score) + ")";
  if (!std::isfinite(min_relative))
    return "sequence evidence minimum relative similarity must be finite (got " + std::to_string(min_relative) + ")";
  if (!(min_share >= 0.0 && min_share <= 1.0))
    return "sequence evidence minimum share must be in [0, 1] (got " + std::to_string(min_share) + ")";
  if (!(weight >= 0.0 && weight <= 1.0)) return "sequence evidence weight must be in [0, 1] (got " + std::to_string(weight) + ")";
  return {};
}

PlaceSequenceEvidence::PlaceSequenceEvidence(const SequenceEvidenceConfig& config, const SimilarityMeasure& similarity)
    : config_(config), similarity_(similarity), detector_(config.loop) {
  if (const std::string problem = config_.validate(); !problem.empty())
    throw std::invalid_argument("PlaceSequenceEvidence: " + problem);
}

void PlaceSequenceEvidence::addFrame(std::int64_t frame, double time_s,
                                     const std::shared_ptr<const Fingerprint>& fingerprint) {
  if (!fingerprint || !std::isfinite(time_s)) return;
  if (!keyframe_frames_.empty() && frame <= keyframe_frames_.back())
    throw std::invalid_argument("PlaceSequenceEvidence::addFrame: frame " + std::to_string(frame) +
                                " after frame " + std::to_string(keyframe_frames_.back()));
  const bool first = keyframe_frames_.empty();
  if (!isKeyframe(first || traversal_break_, time_s, last_keyframe_time_s_, config_.loop.keyframe_interval_s)) return;
  const bool continues = !first && !traversal_break_ && time_s >= last_keyframe_time_s_;
  row_.clear();
  for (const auto& earlier : keyframe_fingerprints_)
    row_.push_back(std::clamp(similarity_.symmetricSimilarity(*earlier, *fingerprint), 0.0, 1.0));
  const SequenceLoopDetector::Detection d = detector_.add(row_, continues);
  KeyframeDetection record{frame, -1};
  if (d.keyframe >= 0 && d.score >= config_.min_score && d.relative >= config_.min_relative) record.matched_frame = keyframe_frames_[static_cast<std::size_t>(d.keyframe)];
  open_detections_.push_back(record);
  keyframe_fingerprints_.push_back(fingerprint);
  keyframe_frames_.push_back(frame);
  last_keyframe_time_s_ = time_s;
  traversal_break_ = false;
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
