// FiedlerSegmenter: cached ring-window affinity, L_sym, lambda2, Algorithm 4.1 and representative
// selection. See the header for the definitions and the reading of the thesis behind them.
#include "toposlam/segmentation/fiedler_segmenter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace toposlam {

namespace {

// A similarity must be a finite non-negative number for the Laplacian to be positive semi-definite.
// Anything else (a bug or a broken measure) is treated as "no link".
double sanitizeSimilarity(double value) {
  if (!std::isfinite(value) || value < 0.0) return 0.0;
  return value;
}

// Fills `laplacian` (top-left k x k) with L_sym of `affinity` (top-left k x k), using the degree-0
// convention of the header: isolated nodes get a zero row/column and a zero diagonal.
void buildSymmetricLaplacian(const Eigen::Ref<const Eigen::MatrixXd>& affinity,
                             Eigen::Ref<Eigen::VectorXd> degree, Eigen::Ref<Eigen::VectorXd> inv_sqrt_degree,
                             Eigen::Ref<Eigen::MatrixXd> laplacian) {
  const Eigen::Index k = affinity.rows();
  degree = affinity.rowwise().sum();
  for (Eigen::Index i = 0; i < k; ++i) {
    inv_sqrt_degree(i) = degree(i) > 0.0 ? 1.0 / std::sqrt(degree(i)) : 0.0;
  }
  for (Eigen::Index j = 0; j < k; ++j) {
    for (Eigen::Index i = 0; i < k; ++i) {
      laplacian(i, j) = -inv_sqrt_degree(i) * affinity(i, j) * inv_sqrt_degree(j);
    }
    // The affinity's diagonal is zero, so L_sym(j, j) = 1 (Chung: 0 for an isolated node).
    laplacian(j, j) = degree(j) > 0.0 ? 1.0 : 0.0;
  }
}

}  // namespace

const char* toString(CutPlacement placement) {
  switch (placement) {
    case CutPlacement::WindowSplit:
      return "window-split";
    case CutPlacement::ValleyFrame:
      return "valley-frame";
  }
  return "?";
}

CutPlacement parseCutPlacement(const std::string& name) {
  if (name == "window-split") return CutPlacement::WindowSplit;
  if (name == "valley-frame") return CutPlacement::ValleyFrame;
  throw std::invalid_argument("cut placement '" + name + "' is unknown: use window-split or valley-frame");
}

const char* toString(RepresentativeChoice choice) {
  switch (choice) {
    case RepresentativeChoice::WindowDegree:
      return "window-degree";
    case RepresentativeChoice::PlaceMedoid:
      return "place-medoid";
  }
  return "?";
}

RepresentativeChoice parseRepresentativeChoice(const std::string& name) {
  if (name == "window-degree") return RepresentativeChoice::WindowDegree;
  if (name == "place-medoid") return RepresentativeChoice::PlaceMedoid;
  throw std::invalid_argument("representative '" + name + "' is unknown: use window-degree or place-medoid");
}

const char* placeEndName(PlaceEnd end) {
  switch (end) {
    case PlaceEnd::Valley: return "valley";
    case PlaceEnd::ValleyAtDoorway: return "valley_at_doorway";
    case PlaceEnd::DoorwayPassage: return "doorway";
    case PlaceEnd::InterruptedValley: return "interrupted_valley";
    case PlaceEnd::StreamEnd: return "stream_end";
  }
  return "unknown";
}

double maxFiedlerValue(int nodes) {
  if (nodes < 2) return 0.0;
  return static_cast<double>(nodes) / static_cast<double>(nodes - 1);
}

std::string FiedlerSegmenterConfig::validate() const {
  // "<key>: <value><unit> is outside the allowed range [lo, hi]<note>" for a real outside [lo, hi] (or NaN).
  const auto outside = [](const char* key, double value, double lo, double hi, const char* unit,
                          const char* note) -> std::optional<std::string> {
    if (value >= lo && value <= hi) return std::nullopt;
    std::ostringstream message;
    message << key << ": " << value << unit << " is outside the allowed range [" << lo << ", " << hi << "]" << note;
    return message.str();
  };
  if (window < 3 || window > 1000) {
    return "window: " + std::to_string(window) + " frames is outside the allowed range [3, 1000]";
  }
  if (auto p = outside("window_s", window_s, 0, 3600, " s", " (0 = count frames)")) return *p;
  if (auto p = outside("window_m", window_m, 0, 1000, " m", " (0 = off)")) return *p;
  if (auto p = outside("min_frame_spacing_m", min_frame_spacing_m, 0, 100, " m", " (0 = off)")) return *p;
  if (auto p = outside("representative_interval_s", representative_interval_s, 0, 3600, " s", " (0 = every frame)")) return *p;
  if (place_samples < 0 || place_samples > kMaxQuerySamples)
    return "place_samples: " + std::to_string(place_samples) + " is outside the allowed range [0, " +
           std::to_string(kMaxQuerySamples) + "]";
  if (place_views < 0 || place_views > kMaxQuerySamples)
    return "place_views: " + std::to_string(place_views) + " is outside the allowed range [0, " +
           std::to_string(kMaxQuerySamples) + "]";
  if (auto p = outside("min_frame_spacing_rad", min_frame_spacing_rad, 0, 10, " rad", "")) return *p;
  if (auto p = outside("doorway_shift_s", doorway_shift_s, 0, 60, " s", " (0 = off)")) return *p;
  if (min_window_frames < 3 || min_window_frames > window) {
    return "min_window_frames: " + std::to_string(min_window_frames) + " is outside the allowed range [3, window = " +
           std::to_string(window) + "]";
  }
  if (std::string problem = valley.validate(maxFiedlerValue(window)); !problem.empty()) return problem;
  if (!(similarity_floor >= 0.0 && similarity_floor < 1.0)) {
    std::ostringstream message;
    message << "similarity_floor: " << similarity_floor << " is outside the allowed range [0, 1)";
    return message.str();
  }
  if (min_keypoints < 0 || min_keypoints > 100000) {
    return "min_keypoints: " + std::to_string(min_keypoints) + " is outside the allowed range [0, 100000]";
  }
  if (cut_placement != CutPlacement::WindowSplit && cut_placement != CutPlacement::ValleyFrame) {
    return "cut_placement: unknown value (allowed: window-split, valley-frame)";
  }
  return "";
}

double fiedlerValue(const Eigen::MatrixXd& affinity) {
  if (affinity.rows() != affinity.cols()) {
    throw std::invalid_argument("fiedlerValue: the affinity matrix must be square, got " +
                                std::to_string(affinity.rows()) + "x" + std::to_string(affinity.cols()));
  }
  const Eigen::Index k = affinity.rows();
  if (k < 2) return 0.0;
  Eigen::MatrixXd links = affinity.unaryExpr([](double v) { return sanitizeSimilarity(v); });
  links.diagonal().setZero();
  Eigen::VectorXd degree(k), inv_sqrt_degree(k);
  Eigen::MatrixXd laplacian(k, k);
  buildSymmetricLaplacian(links, degree, inv_sqrt_degree, laplacian);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(laplacian, Eigen::EigenvaluesOnly);
  return std::max(0.0, solver.eigenvalues()(1));
}

FiedlerSegmenter::FiedlerSegmenter(const FiedlerSegmenterConfig& config, const SimilarityMeasure& similarity)
    : config_(config),
      similarity_(similarity),
      detector_([&config] {
        if (const std::string problem = config.validate(); !problem.empty()) {
          throw std::invalid_argument("segmentation config: " + problem);
        }
        return config.valley;
      }()),
      // Sized once here (after detector_ validated the config): compute() on an n x n matrix then
      // reuses this storage. (Assigning a solver would copy its uninitialised status field.)
      solver_(config.window) {
  const int n = config_.window;
  slot_fingerprint_.resize(static_cast<std::size_t>(n));
  slot_frame_.assign(static_cast<std::size_t>(n), -1);
  slot_time_.assign(static_cast<std::size_t>(n), 0.0);
  slot_distance_.assign(static_cast<std::size_t>(n), std::numeric_limits<double>::quiet_NaN());
  affinity_ = Eigen::MatrixXd::Zero(n, n);
  degree_ = Eigen::VectorXd::Zero(n);
  inv_sqrt_degree_ = Eigen::VectorXd::Zero(n);
  laplacian_ = Eigen::MatrixXd::Zero(n, n);
  candidates_.reserve(static_cast<std::size_t>(4 * n));
  if (config_.doorway_shift_s > 0.0) {
    // A border is at most a window (plus the valley's confirmation) old; frames older than this ring
    // cannot take a moved border.
    const auto recent = static_cast<std::size_t>(4 * n + 64);
    recent_frame_.assign(recent, -1);
    recent_time_.assign(recent, 0.0);
  }
  if (config_.representative == RepresentativeChoice::PlaceMedoid) {
    place_samples_.reserve(FiedlerSegmenterConfig::kMaxPlaceSamples);
    place_sample_affinity_ = Eigen::MatrixXd::Zero(FiedlerSegmenterConfig::kMaxPlaceSamples,
                                                   FiedlerSegmenterConfig::kMaxPlaceSamples);
    sample_interval_s_ = config_.representative_interval_s;
  }
  if (config_.place_samples > 0 || config_.place_views > 0) {
    query_samples_.reserve(FiedlerSegmenterConfig::kMaxPlaceSamples);
    query_sample_interval_s_ = config_.representative_interval_s;
  }
}

void FiedlerSegmenter::sampleQueryFrame(int slot) {
  const auto s = static_cast<std::size_t>(slot);
  if (slot_fingerprint_[s]->keypointCount() < config_.min_keypoints) return;
  const double since_s = slot_time_[s] - last_query_sample_s_;
  // A clock that goes back (a new traversal) always samples.
  if (since_s >= 0.0 && since_s < query_sample_interval_s_ - 1e-9) return;
  if (query_samples_.size() == static_cast<std::size_t>(FiedlerSegmenterConfig::kMaxPlaceSamples)) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < query_samples_.size(); i += 2) query_samples_[kept++] = std::move(query_samples_[i]);
    query_samples_.resize(kept);
    query_sample_interval_s_ *= 2.0;
  }
  query_samples_.push_back(Candidate{slot_frame_[s], 0.0, slot_time_[s], slot_fingerprint_[s],
                                     slot_fingerprint_[s]->keypointCount()});
  last_query_sample_s_ = slot_time_[s];
}

void FiedlerSegmenter::takeQuerySamples(SegmentedPlace& place, std::int64_t last_frame) {
  std::size_t in_place = 0, first = 0;
  while (in_place < query_samples_.size() && query_samples_[in_place].frame <= last_frame) ++in_place;
  while (first < in_place && query_samples_[first].frame < place.first_frame) ++first;
  std::size_t others = 0;
  for (std::size_t i = first; i < in_place; ++i) others += query_samples_[i].frame != place.representative_frame;
  // The k-th of `take` is the ((2k + 1) * others / (2 take))-th other sample: the middles of equal parts.
  const auto spread = [&](int wanted, const auto& keep) {
    const std::size_t take = std::min(others, static_cast<std::size_t>(wanted));
    std::size_t seen = 0, k = 0;
    for (std::size_t i = first; i < in_place && k < take; ++i) {
      if (query_samples_[i].frame == place.representative_frame) continue;
      if (seen == (2 * k + 1) * others / (2 * take)) keep(k++, query_samples_[i].fingerprint);
      ++seen;
    }
    return static_cast<int>(k);
  };
  place.sample_count = spread(config_.place_samples, [&](std::size_t k, const auto& f) { place.samples[k] = f; });
  place.views.clear();
  spread(config_.place_views, [&](std::size_t, const auto& f) { place.views.push_back(f); });
  query_samples_.erase(query_samples_.begin(), query_samples_.begin() + static_cast<std::ptrdiff_t>(in_place));
  query_sample_interval_s_ = config_.representative_interval_s;
}

void FiedlerSegmenter::samplePlaceFrame(int slot) {
  const auto s = static_cast<std::size_t>(slot);
  if (!place_samples_.empty()) {
    const Candidate& last = place_samples_.back();
    const double since_s = slot_time_[s] - last.time_s;
    // A clock that goes back (a new traversal) always samples.
    if (since_s >= 0.0 && (since_s < sample_interval_s_ * (1.0 - 1e-9) || slot_frame_[s] - last.frame < sample_stride_))
      return;
  }
  if (place_samples_.size() == static_cast<std::size_t>(FiedlerSegmenterConfig::kMaxPlaceSamples)) thinPlaceSamples();
  const auto i = static_cast<Eigen::Index>(place_samples_.size());
  for (Eigen::Index j = 0; j < i; ++j) {
    const double value = sanitizeSimilarity(
        similarity_.symmetricSimilarity(*place_samples_[static_cast<std::size_t>(j)].fingerprint, *slot_fingerprint_[s]));
    place_sample_affinity_(i, j) = value;
    place_sample_affinity_(j, i) = value;
  }
  place_sample_affinity_(i, i) = 0.0;
  place_samples_.push_back(Candidate{slot_frame_[s], 0.0, slot_time_[s], slot_fingerprint_[s],
                                     slot_fingerprint_[s]->keypointCount(), static_cast<double>(sample_stride_)});
}

void FiedlerSegmenter::thinPlaceSamples() {
  // Keep samples 0, 2, 4, ...: new index w takes old index 2w. Reading (2a, 2b) never reads a cell
  // already written in this pass, so the matrix is compacted in place.
  const auto count = static_cast<Eigen::Index>(place_samples_.size());
  const Eigen::Index kept = (count + 1) / 2;
  for (Eigen::Index a = 0; a < kept; ++a) {
    for (Eigen::Index b = 0; b < kept; ++b) place_sample_affinity_(a, b) = place_sample_affinity_(2 * a, 2 * b);
    place_samples_[static_cast<std::size_t>(a)] = std::move(place_samples_[static_cast<std::size_t>(2 * a)]);
    place_samples_[static_cast<std::size_t>(a)].weight *= 2.0;  // it now stands for its dropped neighbour too
  }
  place_samples_.resize(static_cast<std::size_t>(kept));
  sample_interval_s_ *= 2.0;
  sample_stride_ *= 2;
}

std::optional<std::pair<int, double>> FiedlerSegmenter::placeMedoid(int count) const {
  // Each other sample weighs as many frames as it stands for, so a stretch sampled before a thinning
  // (or after a reset of the rate) counts as much as the same time sampled densely.
  std::optional<std::pair<int, double>> best;
  Candidate best_candidate{};
  for (int i = 0; i < count; ++i) {
    Candidate candidate = place_samples_[static_cast<std::size_t>(i)];
    candidate.degree = 0.0;
    for (int j = 0; j < count; ++j) candidate.degree += place_sample_affinity_(i, j) * place_samples_[static_cast<std::size_t>(j)].weight;
    if (!best || preferred(candidate, best_candidate)) {
      best = std::make_pair(i, candidate.degree);
      best_candidate = std::move(candidate);
    }
  }
  return best;
}

void FiedlerSegmenter::dropPlaceSamples(int count) {
  const auto total = static_cast<Eigen::Index>(place_samples_.size());
  const Eigen::Index left = total - count;
  for (Eigen::Index a = 0; a < left; ++a) {
    for (Eigen::Index b = 0; b < left; ++b) place_sample_affinity_(a, b) = place_sample_affinity_(a + count, b + count);
  }
  place_samples_.erase(place_samples_.begin(), place_samples_.begin() + count);
  sample_interval_s_ = config_.representative_interval_s;
  sample_stride_ = 1;
}

int FiedlerSegmenter::slotAtPosition(int position) const {
  const int n = config_.window;
  return ((next_slot_ - count_ + position) % n + n) % n;
}

double FiedlerSegmenter::computeLambda2() {
  const int k = count_;
  const int n = config_.window;
  if (k == n) {
    // Every slot is in the window (order does not matter for eigenvalues): the full matrices.
    buildSymmetricLaplacian(affinity_, degree_, inv_sqrt_degree_, laplacian_);
    solver_.compute(laplacian_, Eigen::EigenvaluesOnly);
    return std::max(0.0, solver_.eigenvalues()(1));
  }
  // Degrees per slot (other code reads degree_ by slot), then L_sym in window order in the top-left
  // k x k of the scratch matrix. Eigenvalues do not depend on the order. At a steady frame rate k is
  // constant, so the solver's storage is reused and nothing is allocated.
  for (int a = 0; a < k; ++a) {
    const int sa = slotAtPosition(a);
    double d = 0.0;
    for (int b = 0; b < k; ++b) d += affinity_(sa, slotAtPosition(b));
    degree_(sa) = d;
    inv_sqrt_degree_(sa) = d > 0.0 ? 1.0 / std::sqrt(d) : 0.0;
  }
  for (int b = 0; b < k; ++b) {
    const int sb = slotAtPosition(b);
    for (int a = 0; a < k; ++a) {
      const int sa = slotAtPosition(a);
      laplacian_(a, b) = -inv_sqrt_degree_(sa) * affinity_(sa, sb) * inv_sqrt_degree_(sb);
    }
    laplacian_(b, b) = degree_(sb) > 0.0 ? 1.0 : 0.0;
  }
  solver_.compute(laplacian_.topLeftCorner(k, k), Eigen::EigenvaluesOnly);
  // L_sym is positive semi-definite; clamp round-off below zero.
  return std::max(0.0, solver_.eigenvalues()(1));
}

void FiedlerSegmenter::addCandidate(const Candidate& candidate) {
  for (Candidate& existing : candidates_) {
    if (existing.frame == candidate.frame) {
      if (candidate.degree > existing.degree) existing.degree = candidate.degree;
      return;
    }
  }
  candidates_.push_back(candidate);
  if (candidates_.size() > static_cast<std::size_t>(2 * config_.window)) compactCandidates();
}

void FiedlerSegmenter::compactCandidates() {
  // Every future border is at or after `bound`: a future valley's split lies after the oldest frame of
  // the current window, and a pending one is known. Candidates before it all belong to the open place,
  // so only their best can ever be chosen.
  std::int64_t bound = slot_frame_[static_cast<std::size_t>(slotAtPosition(0))];
  if (!detector_.lookingForPeak() && pending_min_frame_ >= 0 && pending_min_frame_ == detector_.minIndex()) {
    bound = std::min(bound, pending_border_frame_ >= 0 ? pending_border_frame_ : pending_min_frame_ + 1);
  }
  const Candidate* best = nullptr;
  for (const Candidate& c : candidates_) {
    if (c.frame < bound && (best == nullptr || preferred(c, *best))) best = &c;
  }
  if (best == nullptr) return;
  const std::int64_t keep = best->frame;
  std::erase_if(candidates_, [&](const Candidate& c) { return c.frame < bound && c.frame != keep; });
}

void FiedlerSegmenter::rememberBestWindowFrame(std::int64_t from_frame, std::int64_t before_frame) {
  std::optional<Candidate> best;
  for (int position = 0; position < count_; ++position) {
    const int slot = slotAtPosition(position);
    const auto s = static_cast<std::size_t>(slot);
    const std::int64_t frame = slot_frame_[s];
    if (frame < from_frame || frame >= before_frame) continue;
    Candidate candidate{frame, degree_(slot), slot_time_[s], slot_fingerprint_[s], slot_fingerprint_[s]->keypointCount()};
    if (!best || preferred(candidate, *best)) best = std::move(candidate);
  }
  if (best) addCandidate(*best);
}

bool FiedlerSegmenter::preferred(const Candidate& a, const Candidate& b) const {
  const bool a_rich = a.keypoints >= config_.min_keypoints;
  const bool b_rich = b.keypoints >= config_.min_keypoints;
  if (a_rich != b_rich) return a_rich;
  if (a.degree != b.degree) return a.degree > b.degree;
  return a.frame < b.frame;
}

int FiedlerSegmenter::bestSplitPosition() const {
  // Sweep the temporal splits [0, t) | [t, k) of the window and take the smallest normalised cut.
  // cut(t+1) = cut(t) - sum_{i<t} a(i,t) + sum_{j>t} a(t,j); vol = prefix sums of the degrees.
  const int k = count_;
  double total_volume = 0.0;
  for (int p = 0; p < k; ++p) total_volume += degree_(slotAtPosition(p));
  double cut = 0.0;
  double volume_before = 0.0;
  double best_value = std::numeric_limits<double>::infinity();
  int best_position = -1;
  for (int t = 1; t < k; ++t) {
    const int moved = slotAtPosition(t - 1);  // the frame that moves from the newer to the older part
    for (int p = 0; p < k; ++p) {
      if (p == t - 1) continue;
      const double a = affinity_(moved, slotAtPosition(p));
      cut += p < t - 1 ? -a : a;
    }
    volume_before += degree_(moved);
    const std::int64_t first_newer = slot_frame_[static_cast<std::size_t>(slotAtPosition(t))];
    if (first_newer <= place_start_) continue;  // the border must fall inside the open place
    const double volume_after = total_volume - volume_before;
    if (volume_before <= 0.0 || volume_after <= 0.0) continue;
    const double value = std::max(0.0, cut) * (1.0 / volume_before + 1.0 / volume_after);
    if (value < best_value) {
      best_value = value;
      best_position = t;
    }
  }
  return best_position;
}

SegmenterStep FiedlerSegmenter::addFrame(std::int64_t frame_index, double time_s,
                                         std::shared_ptr<const Fingerprint> fingerprint) {
  return addFrameAt(frame_index, time_s, std::move(fingerprint), std::numeric_limits<double>::quiet_NaN());
}

void FiedlerSegmenter::checkNextFrame(std::int64_t frame_index, const Fingerprint* fingerprint) const {
  if (fingerprint == nullptr) throw std::invalid_argument("FiedlerSegmenter::addFrame: null fingerprint");
  if (frame_index <= last_frame_) {
    throw std::invalid_argument("FiedlerSegmenter::addFrame: frame " + std::to_string(frame_index) +
                                " does not follow frame " + std::to_string(last_frame_) +
                                " (frame indices must increase)");
  }
}

SegmenterStep FiedlerSegmenter::addFrame(std::int64_t frame_index, double time_s,
                                         std::shared_ptr<const Fingerprint> fingerprint, const MotionState& motion) {
  if (!motion.known) return addFrame(frame_index, time_s, std::move(fingerprint));
  const double distance_m =
      std::isfinite(motion.distance_m) ? motion.distance_m : std::numeric_limits<double>::quiet_NaN();
  // Left out: the robot stands, or (frame spacing) the frame is too close to the last one added, in
  // travel and in heading.
  const bool too_close = config_.window_m > 0.0 && config_.min_frame_spacing_m > 0.0 && std::isfinite(distance_m) &&
                         std::isfinite(last_added_distance_m_) && distance_m >= last_added_distance_m_ &&
                         distance_m - last_added_distance_m_ < config_.min_frame_spacing_m &&
                         motion.turned_rad - last_added_turned_rad_ < config_.min_frame_spacing_rad;
  if (motion.standing || too_close) {
    checkNextFrame(frame_index, fingerprint.get());
    ++(motion.standing ? skipped_frames_ : thinned_frames_);
    SegmenterStep step;
    step.frame = frame_index;
    step.skipped = true;
    return step;
  }
  if (std::isfinite(distance_m)) {
    last_added_distance_m_ = distance_m;
    last_added_turned_rad_ = motion.turned_rad;
  }
  return addFrameAt(frame_index, time_s, std::move(fingerprint), distance_m);
}

SegmenterStep FiedlerSegmenter::addFrameAt(std::int64_t frame_index, double time_s,
                                           std::shared_ptr<const Fingerprint> fingerprint, double distance_m) {
  checkNextFrame(frame_index, fingerprint.get());
  // ValleyFrame: the border after a recorded minimum is the frame that follows it.
  if (pending_min_frame_ >= 0 && pending_min_frame_ == last_frame_ && pending_border_frame_ < 0 &&
      config_.cut_placement == CutPlacement::ValleyFrame) {
    pending_border_frame_ = frame_index;
    pending_border_time_s_ = time_s;
  }

  const int n = config_.window;
  // The ring is full: the oldest frame leaves to make room.
  if (count_ == n) {
    --count_;
    window_full_ = true;
  }
  // A window in time: frames taken window_s or more before this one leave (keeping min_window_frames).
  // A clock that goes back (a new traversal) leaves them all in: only the ring's size then evicts.
  // A window in distance (motion known for this frame): frames taken window_m or more of travel before
  // this one leave; an older frame without a distance (taken while motion was unknown) leaves by time.
  const bool by_distance = config_.window_m > 0.0 && std::isfinite(distance_m);
  if (by_distance) {
    const double tolerance_m = 1e-6 * config_.window_m;
    const double tolerance_s = 1e-6 * config_.window_s;
    while (count_ >= config_.min_window_frames) {
      const auto oldest = static_cast<std::size_t>(slotAtPosition(0));
      const double oldest_distance = slot_distance_[oldest];
      if (std::isfinite(oldest_distance)) {
        if (!(distance_m - oldest_distance >= config_.window_m - tolerance_m)) break;
      } else if (!(config_.window_s > 0.0 && time_s - slot_time_[oldest] >= config_.window_s - tolerance_s)) {
        break;
      }
      --count_;
      window_full_ = true;
    }
  } else if (config_.window_s > 0.0) {
    const double tolerance = 1e-6 * config_.window_s;
    while (count_ >= config_.min_window_frames) {
      const double oldest_time = slot_time_[static_cast<std::size_t>(slotAtPosition(0))];
      if (!(time_s - oldest_time >= config_.window_s - tolerance)) break;
      --count_;
      window_full_ = true;
    }
  }
  const int slot = next_slot_;
  const auto s = static_cast<std::size_t>(slot);
  slot_fingerprint_[s] = std::move(fingerprint);
  slot_frame_[s] = frame_index;
  slot_time_[s] = time_s;
  slot_distance_[s] = distance_m;
  // Only the new frame's row and column are new: 2 (k-1) similarity calls. Slots outside the window
  // are never read, so their rows are not cleared.
  affinity_(slot, slot) = 0.0;
  for (int position = 0; position < count_; ++position) {
    const int other = slotAtPosition(position);
    double value = sanitizeSimilarity(
        similarity_.symmetricSimilarity(*slot_fingerprint_[static_cast<std::size_t>(other)], *slot_fingerprint_[s]));
    value = std::max(0.0, value - config_.similarity_floor);
    affinity_(slot, other) = value;
    affinity_(other, slot) = value;
  }
  ++count_;
  next_slot_ = (slot + 1) % n;
  if (config_.window_s <= 0.0 && count_ == n) window_full_ = true;
  last_frame_ = frame_index;
  last_time_s_ = time_s;
  if (place_start_ < 0) {
    place_start_ = frame_index;
    place_start_time_s_ = time_s;
  }
  if (config_.doorway_shift_s > 0.0) {
    // A time that does not increase is a new traversal: the detector forgets its passages.
    if (recent_count_ > 0 && !(time_s > recent_time_[(recent_next_ + recent_frame_.size() - 1) % recent_frame_.size()]))
      passages_done_s_ = -std::numeric_limits<double>::infinity();
    const Fingerprint& added = *slot_fingerprint_[s];
    doorway_.addFrame(time_s, added.image_width, added.edge_columns);
    recent_frame_[recent_next_] = frame_index;
    recent_time_[recent_next_] = time_s;
    recent_next_ = (recent_next_ + 1) % recent_frame_.size();
    recent_count_ = std::min(recent_count_ + 1, recent_frame_.size());
  }

  SegmenterStep step;
  step.frame = frame_index;
  if (count_ >= 2) {
    step.lambda2 = computeLambda2();
  } else {
    degree_.setZero();
  }
  rememberBestWindowFrame(place_start_, std::numeric_limits<std::int64_t>::max());
  if (config_.representative == RepresentativeChoice::PlaceMedoid) samplePlaceFrame(slot);
  if (config_.place_samples > 0 || config_.place_views > 0) sampleQueryFrame(slot);

  // The detector sees lambda2 only once the window is full: while it fills, lambda2 of a perfectly
  // connected window falls as k/(k-1) (2, 1.5, 1.33, ...), which would read as a peak.
  if (window_full_ && step.lambda2) {
    const std::optional<std::int64_t> valley = detector_.update(frame_index, *step.lambda2);
    if (!detector_.lookingForPeak() && detector_.minIndex() == frame_index) {
      // A new minimum: remember where its border would be and a candidate before that border.
      pending_min_frame_ = frame_index;
      pending_border_frame_ = -1;
      if (config_.cut_placement == CutPlacement::WindowSplit) {
        const int position = bestSplitPosition();
        if (position > 0) {
          const int border_slot = slotAtPosition(position);
          const int last_slot = slotAtPosition(position - 1);
          pending_border_frame_ = slot_frame_[static_cast<std::size_t>(border_slot)];
          pending_border_time_s_ = slot_time_[static_cast<std::size_t>(border_slot)];
          pending_last_frame_ = slot_frame_[static_cast<std::size_t>(last_slot)];
          pending_last_time_s_ = slot_time_[static_cast<std::size_t>(last_slot)];
          rememberBestWindowFrame(place_start_, pending_border_frame_);
        }
      } else {
        pending_last_frame_ = frame_index;
        pending_last_time_s_ = time_s;
        rememberBestWindowFrame(place_start_, frame_index + 1);
      }
    }
    if (valley) {
      if (pending_min_frame_ == *valley && pending_border_frame_ > place_start_) {
        if (config_.doorway_shift_s <= 0.0 || moveBorderToDoorway()) {
          step.closed_place = closePlace(*valley, pending_last_frame_, pending_last_time_s_, pending_border_frame_,
                                         pending_border_time_s_, pending_border_passage_s_);
          step.closed_place->end =
              std::isnan(pending_border_passage_s_) ? PlaceEnd::Valley : PlaceEnd::ValleyAtDoorway;
        } else {
          ++ignored_valleys_;
          ++doorway_repeats_;
        }
      } else {
        ++ignored_valleys_;
      }
      pending_min_frame_ = -1;
      pending_border_frame_ = -1;
    }
  }
  // A doorway passage the frames have reached closes the open place there, unless a border is already
  // on it (one passage per frame; a place closed by a valley in this frame makes it wait for the next).
  if (passagesMakeBorders() && !step.closed_place) {
    const std::optional<double> due = doorway_.firstPassageAfter(passages_done_s_);
    if (due && time_s >= *due) {
      // A valley the passage interrupts closes its place first; the passage closes the next one at the
      // next frame (it is still due then).
      step.closed_place = closePlaceAtInterruptedValley(*due);
      if (!step.closed_place) {
        passages_done_s_ = *due;
        step.closed_place = closePlaceAtPassage(*due);
      }
    }
  }
  return step;
}

FiedlerSegmenter::RecentBorder FiedlerSegmenter::recentBorderAt(double time_s) const {
  // The first recent frame at or after time_s, and the one before it (the closing place's last). A
  // time still ahead (a passage predicted before the robot gets there) takes the newest frame: a place
  // cannot start at a frame not seen yet.
  RecentBorder at;
  const std::size_t size = recent_frame_.size();
  const std::size_t oldest = recent_count_ < size ? 0 : recent_next_;
  for (std::size_t k = 0; k < recent_count_; ++k) {
    const std::size_t i = (oldest + k) % size;
    if (recent_time_[i] >= time_s) {
      at.border = recent_frame_[i];
      at.border_time_s = recent_time_[i];
      return at;
    }
    at.last = recent_frame_[i];
    at.last_time_s = recent_time_[i];
  }
  if (recent_count_ >= 2) {
    const std::size_t newest = (recent_next_ + size - 1) % size;
    const std::size_t before = (recent_next_ + size - 2) % size;
    at.border = recent_frame_[newest];
    at.border_time_s = recent_time_[newest];
    at.last = recent_frame_[before];
    at.last_time_s = recent_time_[before];
  }
  return at;
}

std::optional<SegmentedPlace> FiedlerSegmenter::closePlaceAtPassage(double passage_s) {
  // A border already on this passage (a valley's, moved to it), a passage before the open place, or
  // one older than the recent frames: nothing to close.
  if (passage_s == place_start_passage_s_) return std::nullopt;
  const RecentBorder at = recentBorderAt(passage_s);
  if (at.border < 0 || at.last < 0 || at.border <= place_start_) return std::nullopt;
  rememberBestWindowFrame(place_start_, at.border);
  const std::int64_t from = std::max(place_start_, representative_from_);
  const std::int64_t to = std::min(at.last, representative_last_);
  if (!hasCandidateIn(from, to)) return std::nullopt;
  SegmentedPlace place = closePlace(at.border, at.last, at.last_time_s, at.border, at.border_time_s, passage_s);
  place.end = PlaceEnd::DoorwayPassage;
  ++doorway_borders_;
  return place;
}

std::optional<SegmentedPlace> FiedlerSegmenter::closePlaceAtInterruptedValley(double passage_s) {
  // A valley whose fall is confirmed (a peak, then lambda2 down by delta) but whose rise is not yet:
  // its border candidate is inside the open place, before the passage.
  if (detector_.lookingForPeak() || pending_min_frame_ < 0 || pending_min_frame_ != detector_.minIndex()) {
    return std::nullopt;
  }
  if (pending_border_frame_ <= place_start_ || passage_s == place_start_passage_s_) return std::nullopt;
  const RecentBorder at = recentBorderAt(passage_s);
  if (at.border < 0 || at.last < 0 || pending_border_frame_ >= at.border) return std::nullopt;
  // Both places must span a window: a shorter stretch is the view changing on the way to the door (the
  // door's own valley, which the passage's border stands for), or a stretch no window could find alone.
  if (config_.window_s > 0.0) {
    const double tolerance = 1e-6 * config_.window_s;
    if (pending_border_time_s_ - place_start_time_s_ < config_.window_s - tolerance) return std::nullopt;
    if (at.border_time_s - pending_border_time_s_ < config_.window_s - tolerance) return std::nullopt;
  } else if (pending_border_frame_ - place_start_ < config_.window || at.border - pending_border_frame_ < config_.window) {
    return std::nullopt;
  }
  const std::int64_t from = std::max(place_start_, representative_from_);
  if (!hasCandidateIn(from, std::min(pending_last_frame_, representative_last_))) return std::nullopt;
  if (!hasCandidateIn(pending_border_frame_, at.last)) return std::nullopt;
  SegmentedPlace place = closePlace(pending_min_frame_, pending_last_frame_, pending_last_time_s_, pending_border_frame_,
                                    pending_border_time_s_, std::numeric_limits<double>::quiet_NaN());
  place.end = PlaceEnd::InterruptedValley;
  // The passage takes the valley's rise: look for the next peak from here.
  detector_.reset();
  pending_min_frame_ = -1;
  pending_border_frame_ = -1;
  ++interrupted_valleys_;
  return place;
}

bool FiedlerSegmenter::hasCandidateIn(std::int64_t from, std::int64_t to) const {
  return std::any_of(candidates_.begin(), candidates_.end(),
                     [&](const Candidate& c) { return c.frame >= from && c.frame <= to; });
}

bool FiedlerSegmenter::moveBorderToDoorway() {
  pending_border_passage_s_ = std::numeric_limits<double>::quiet_NaN();
  const std::optional<double> passage = doorway_.nearestPassage(pending_border_time_s_, config_.doorway_shift_s);
  if (!passage) return true;
  if (passagesMakeBorders() && *passage == place_start_passage_s_) {
    // The open place began at this doorway: a second border for it is where the view changes again
    // after the door (the robot turning into the corridor). Dropped; the place's representative comes
    // from the frames after it, the view the place settles on.
    representative_from_ = std::max(representative_from_, pending_border_frame_);
    return false;
  }
  const RecentBorder at = recentBorderAt(*passage);
  const std::int64_t border = at.border, last = at.last;
  if (border < 0 || last < 0 || border <= place_start_ || border == pending_border_frame_) return true;
  const std::int64_t from = std::max(place_start_, representative_from_);
  const std::int64_t to = std::min(pending_last_frame_, last);
  if (!hasCandidateIn(from, to)) return true;
  // The representatives stay within the borders found by appearance: the frames a shift moves into a
  // place look like its neighbour (the room seen through the door, the corridor seen on the way out).
  representative_last_ = to;
  next_representative_from_ = std::max(border, pending_border_frame_);
  pending_border_frame_ = border;
  pending_border_time_s_ = at.border_time_s;
  pending_last_frame_ = last;
  pending_last_time_s_ = at.last_time_s;
  ++doorway_shifts_;
  pending_border_passage_s_ = *passage;
  return true;
}

SegmentedPlace FiedlerSegmenter::closePlace(std::int64_t valley_frame, std::int64_t last_frame_of_place,
                                            double last_time_s, std::int64_t next_start_frame,
                                            double next_start_time_s, double next_start_passage_s) {
  SegmentedPlace place;
  place.first_frame = place_start_;
  place.first_time_s = place_start_time_s_;
  place.last_frame = last_frame_of_place;
  place.last_time_s = last_time_s;
  place.valley_frame = valley_frame;
  const std::int64_t last_frame = place.last_frame;
  // Representative candidates: the place's frames, within the borders found by appearance when a
  // border was moved to a doorway (moveBorderToDoorway).
  const std::int64_t candidates_from = std::max(place_start_, representative_from_);
  const std::int64_t candidates_to = std::min(last_frame, representative_last_);

  const Candidate* best = nullptr;
  for (const Candidate& c : candidates_) {
    if (c.frame < candidates_from || c.frame > candidates_to) continue;
    if (best == nullptr || preferred(c, *best)) best = &c;
  }
  if (config_.representative == RepresentativeChoice::PlaceMedoid) {
    // The place's samples are the first ones (older samples went with the places before it).
    int in_place = 0;
    while (in_place < static_cast<int>(place_samples_.size()) &&
           place_samples_[static_cast<std::size_t>(in_place)].frame <= last_frame)
      ++in_place;
    if (const auto medoid = placeMedoid(in_place)) {
      const Candidate& sample = place_samples_[static_cast<std::size_t>(medoid->first)];
      place.representative_frame = sample.frame;
      place.representative_degree = medoid->second;
      place.representative = sample.fingerprint;
      place.representative_keypoints = sample.keypoints;
      best = nullptr;  // a place without samples (shorter than the interval) keeps the window's choice
    }
    dropPlaceSamples(in_place);
  }
  if (best != nullptr) {
    place.representative_frame = best->frame;
    place.representative_degree = best->degree;
    place.representative = best->fingerprint;
    place.representative_keypoints = best->keypoints;
  }
  if (config_.place_samples > 0 || config_.place_views > 0) takeQuerySamples(place, last_frame);
  place.dropped = place.representative_keypoints < config_.min_keypoints;
  place.index = place.dropped ? dropped_places_++ : kept_places_++;

  std::erase_if(candidates_, [&](const Candidate& c) { return c.frame <= last_frame; });
  representative_from_ = next_representative_from_;
  representative_last_ = std::numeric_limits<std::int64_t>::max();
  next_representative_from_ = -1;
  place_start_ = next_start_frame;
  place_start_time_s_ = next_start_time_s;
  place_start_passage_s_ = next_start_passage_s;
  return place;
}

std::optional<SegmentedPlace> FiedlerSegmenter::flush() {
  if (place_start_ < 0 || place_start_ > last_frame_) return std::nullopt;
  rememberBestWindowFrame(place_start_, last_frame_ + 1);
  SegmentedPlace place = closePlace(-1, last_frame_, last_time_s_, -1, 0.0, std::numeric_limits<double>::quiet_NaN());
  place.end = PlaceEnd::StreamEnd;
  place_start_ = -1;  // the next frame added opens a new place
  pending_min_frame_ = -1;
  pending_border_frame_ = -1;
  return place;
}

Eigen::MatrixXd FiedlerSegmenter::affinityInWindowOrder() const {
  Eigen::MatrixXd ordered(count_, count_);
  for (int i = 0; i < count_; ++i) {
    for (int j = 0; j < count_; ++j) ordered(i, j) = affinity_(slotAtPosition(i), slotAtPosition(j));
  }
  return ordered;
}

}  // namespace toposlam
