// Adapters from the pipeline's stage interfaces to the algorithm classes; see the header.
#include "toposlam/pipeline/algorithm_stages.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <iterator>
#include <map>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>

#include "toposlam/pipeline/map_files.hpp"
#include "toposlam/topology/map_store.hpp"

namespace toposlam {

FingerprintedFrame VpackFingerprintStage::process(const cv::Mat& image, const cv::Mat& grey) {
  FingerprintedFrame out{extractor_.extract(image, grey), cv::Mat()};
  if (thumbnail_width_ > 0) {
    const int width = std::min(thumbnail_width_, image.cols);
    const double scaled_rows = static_cast<double>(image.rows) * width / image.cols;
    const int height = std::max(1, static_cast<int>(std::lround(scaled_rows)));
    cv::resize(image, out.thumbnail, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------------

FiedlerSegmentationStage::FiedlerSegmentationStage(const FiedlerSegmenterConfig& config,
                                                   const SimilarityMeasure& similarity,
                                                   std::size_t max_thumbnails, const MotionGateConfig& motion,
                                                   const SequenceEvidenceConfig& evidence)
    : similarity_(similarity),
      memo_(similarity),
      segmenter_(std::in_place, config, memo_),
      evidence_(evidence.weight > 0.0 || evidence.frame_revisits ? std::make_unique<PlaceSequenceEvidence>(evidence, memo_)
                                                                  : nullptr),
      evidence_to_filter_(evidence.weight > 0.0),
      max_thumbnails_(std::max<std::size_t>(1, max_thumbnails)),
      gate_(motion) {
  thumbnails_.reserve(max_thumbnails_ + 1);
}

void FiedlerSegmentationStage::addMotion(const MotionSample& sample) {
  const std::lock_guard<std::mutex> lock(motion_mutex_);
  if (pending_motion_.size() >= kMaxPendingMotion) {
    pending_motion_.pop_front();
    ++dropped_motion_;
  }
  pending_motion_.push_back(sample);
}

MotionUse FiedlerSegmentationStage::motionUse() const {
  if (last_motion_.known) return MotionUse::Used;
  if (gate_.refusedSinceAccepted() > 0) return MotionUse::Stale;
  return gate_.samples() > 0 ? MotionUse::Lost : MotionUse::None;
}

// A refusal is the world's bad input: logged for the first few of each reason, then every 1000th.
void FiedlerSegmentationStage::warnOfRefusals(const MotionRefusals& before) const {
  const MotionRefusals& now = gate_.refusals();
  const auto warn = [](std::int64_t was, std::int64_t is, const char* why) {
    for (std::int64_t n = was + 1; n <= is; ++n)
      if (n <= 3 || n % 1000 == 0) {
        spdlog::warn("segmentation: motion sample refused: {} ({} such so far; segmentation.motion)", why, n);
        return;
      }
  };
  warn(before.not_finite, now.not_finite, "a value is not finite");
  warn(before.off_clock, now.off_clock, "its time is further from the receiver's clock than clock_tolerance_s");
  warn(before.implausible, now.implausible, "faster or turning faster than max_speed_mps / max_turn_rate_rps");
  warn(before.earlier, now.earlier, "earlier than the newest sample");
}

std::int64_t FiedlerSegmentationStage::droppedMotionSamples() const {
  const std::lock_guard<std::mutex> lock(motion_mutex_);
  return dropped_motion_;
}

SegmentationStep FiedlerSegmentationStage::process(std::int64_t sequence, double source_time_s, double captured_at_s,
                                                   std::shared_ptr<const Fingerprint> fingerprint,
                                                   const cv::Mat& thumbnail) {
  {
    const std::lock_guard<std::mutex> lock(motion_mutex_);
    applying_.swap(pending_motion_);
  }
  const MotionRefusals refused_before = gate_.refusals();
  for (const MotionSample& m : applying_)
    gate_.addSample(m.time_s, m.distance_increment_m, m.speed_mps, m.turn_rate_rps, m.received_s);
  applying_.clear();
  warnOfRefusals(refused_before);
  const bool was_known = last_motion_.known;
  last_motion_ = gate_.at(captured_at_s);
  if (last_motion_.known != was_known) {
    if (last_motion_.known) {
      spdlog::info("segmentation: robot motion known; standing frames skipped{}",
                   segmenter_->config().window_m > 0.0 ? ", window in metres" : "");
    } else if (gate_.refusedSinceAccepted() > 0) {
      spdlog::warn("segmentation: robot motion stale (no usable sample for {} s, {} refused since the last one); "
                   "segmenting by time",
                   gate_.config().timeout_s, gate_.refusedSinceAccepted());
    } else if (gate_.samples() > 0) {
      spdlog::warn("segmentation: robot motion lost (no sample for {} s); segmenting by time",
                   gate_.config().timeout_s);
    }
  }
  // Kept as a map from frame to thumbnail would be (a frame seen twice keeps its first thumbnail; beyond
  // max_thumbnails_ the lowest frame goes), in a vector reserved once.
  auto same_frame = [&](const auto& entry) { return entry.first == sequence; };
  if (std::none_of(thumbnails_.begin(), thumbnails_.end(), same_frame)) {
    thumbnails_.emplace_back(sequence, thumbnail);
    if (thumbnails_.size() > max_thumbnails_)
      thumbnails_.erase(std::min_element(thumbnails_.begin(), thumbnails_.end(),
                                         [](const auto& a, const auto& b) { return a.first < b.first; }));
  }
  // The window's clock is the frame's source time (a window in seconds of the world, also when a file or
  // the simulator plays faster than real time); motion is looked up at the pipeline clock, the clock of
  // motion_t.utime. A source time that goes back is carried on from the previous frame (FrameTimeline),
  // so the window neither keeps every frame "from the future" nor turns into a window of frames; one that
  // does not increase (a source without timestamps) advances by a second, as before.
  const std::int64_t steps_back = timeline_.stepsBack();
  const double time_s = timeline_.place(source_time_s);
  last_time_s_ = time_s;
  if (timeline_.stepsBack() > steps_back && (steps_back < 10 || steps_back % 1000 == 0))
    spdlog::warn("segmentation: frame {}'s source time went back {:.3f} s (to {:.3f} s); the window's clock carries on "
                 "from the frame before ({} such steps so far)",
                 sequence, timeline_.lastStepBackS(), source_time_s, steps_back + 1);
  FrameRevisit revisit;
  SegmenterStep step;
  {
    // The detector and the segmenter compare this frame with the same earlier ones: once each.
    struct FrameScope {
      FrameSimilarityMemo& memo;
      ~FrameScope() { memo.endFrame(); }
    } scope{memo_};
    memo_.beginFrame(fingerprint.get());
    if (evidence_) revisit = evidence_->addFrame(sequence, time_s, fingerprint);
    step = segmenter_->addFrame(sequence, time_s, std::move(fingerprint), last_motion_);
  }
  if (motion_counters_ != nullptr) {
    motion_counters_->use.store(static_cast<int>(motionUse()));
    motion_counters_->standing_frames.store(skippedFrames());
    motion_counters_->refused.store(gate_.rejectedSamples());
  }
  SegmentationStep out;
  last_closed_.reset();
  if (step.lambda2) out.lambda2 = *step.lambda2;
  if (step.closed_place) out.closed = toClosedPlace(*step.closed_place);
  out.revisit.match_frame = revisit.match_frame;
  out.revisit.score = revisit.score;
  return out;
}

std::optional<ClosedPlace> FiedlerSegmentationStage::finish() {
  last_closed_.reset();
  const std::optional<SegmentedPlace> last = segmenter_->flush();
  if (!last) return std::nullopt;
  return toClosedPlace(*last);
}

void FiedlerSegmentationStage::beginTraversal() {
  kept_before_ = kept_places_;
  dropped_before_ = dropped_places_;
  skipped_before_ += segmenter_->skippedFrames();
  const FiedlerSegmenterConfig config = segmenter_->config();  // a copy: emplace() destroys the old one first
  segmenter_.emplace(config, memo_);
  timeline_ = FrameTimeline{};
  if (evidence_) evidence_->beginTraversal();
  thumbnails_.clear();
}

std::optional<ClosedPlace> FiedlerSegmentationStage::toClosedPlace(const SegmentedPlace& closed) {
  SegmentedPlace p = closed;
  p.index += p.dropped ? dropped_before_ : kept_before_;  // numbered over the run, not the traversal
  std::optional<ClosedPlace> out;
  if (p.dropped) {
    ++dropped_places_;
  } else {
    ++kept_places_;
    ClosedPlace place;
    place.place = static_cast<int>(p.index);
    place.first_frame = p.first_frame;
    place.last_frame = p.last_frame;
    place.representative_frame = p.representative_frame;
    place.keypoints = p.representative_keypoints;
    place.representative = p.representative;
    place.samples.assign(p.samples.begin(), p.samples.begin() + p.sample_count);
    place.views = std::move(p.views);
    if (evidence_) {
      std::vector<double> evidence = evidence_->closePlace(p.first_frame, p.last_frame);
      if (evidence_to_filter_) place.evidence = std::move(evidence);
    }
    const auto it = std::find_if(thumbnails_.begin(), thumbnails_.end(),
                                 [&](const auto& entry) { return entry.first == p.representative_frame; });
    if (it != thumbnails_.end()) place.thumbnail = it->second;
    out = std::move(place);
  }
  // Frames up to the closed place's end are no longer needed.
  std::erase_if(thumbnails_, [&](const auto& entry) { return entry.first <= p.last_frame; });
  p.representative.reset();  // the topology stage holds it as long as it needs it
  p.samples = {};
  p.sample_count = 0;
  p.views.clear();
  last_closed_ = std::move(p);
  return out;
}

// ---------------------------------------------------------------------------------------------------------

ParticleFilterTopologyStage::ParticleFilterTopologyStage(const TopologyFilterConfig& config,
                                                         const SimilarityMeasure& similarity, const Clock& clock,
                                                         const TopologyStageConfig& stage)
    : similarity_(similarity),
      clock_(clock),
      slice_items_(static_cast<std::size_t>(std::max(1, stage.slice_items))),
      alternatives_(std::max(0, stage.alternatives)),
      candidates_(config.candidates),
      filter_(std::make_unique<TopologyParticleFilter>(config, similarity)) {
  topology_.particles = config.particles;
}

ParticleFilterTopologyStage::~ParticleFilterTopologyStage() = default;

void ParticleFilterTopologyStage::loadMap(const std::string& path) { adoptMap(MapStore::load(path, similarity_)); }

void ParticleFilterTopologyStage::adoptMap(LoadedMap loaded) {
  filter_ = std::move(loaded.filter);
  views_ = std::move(loaded.views);
  views_.resize(static_cast<std::size_t>(filter_->observationCount()));
  filter_->setCandidateSelection(candidates_);  // how this process compares, not saved with the map
  topology_.particles = filter_->config().particles;  // the map's, as every other setting of its filter
  // The application data lists the representative frames of the run that saved the map; frame numbers of
  // an older run mean nothing in this one, so resumed observations show -1.
  representative_frames_.assign(static_cast<std::size_t>(filter_->observationCount()), -1);
  run_first_observation_ = filter_->observationCount();
  spans_.clear();  // frame numbers of an older run mean nothing in this one
  last_mapped_frame_ = -1;  // where the source stands in it: the daemon says (setLastMappedFrame)
  last_mapped_name_.clear();
  revision_ = 1;
  refresh();
}

MapNodes mapNodesOf(const TopologyParticleFilter& filter, const PlaceViews& views) {
  MapNodes out;
  if (filter.observationCount() == 0) throw std::invalid_argument("the map has no places to localise against");
  const TopologyEstimate estimate = filter.estimate(1);
  const std::vector<int>& assignment = estimate.best.assignment;
  const int node_count = estimate.best.node_count;
  std::vector<std::vector<Fingerprint>> references(static_cast<std::size_t>(node_count));
  std::map<std::pair<int, int>, int> edges;
  for (std::size_t k = 0; k < assignment.size(); ++k) {
    const int node = assignment[k];
    if (node < 0 || node >= node_count) continue;
    if (const std::shared_ptr<const Fingerprint> f = filter.storedRepresentative(static_cast<int>(k)))
      references[static_cast<std::size_t>(node)].push_back(*f);
    if (k < views.size())
      for (const auto& view : views[k])
        if (view) references[static_cast<std::size_t>(node)].push_back(*view);
    if (k > 0 && assignment[k - 1] >= 0 && assignment[k - 1] != node) ++edges[{assignment[k - 1], node}];
  }
  std::vector<int> index_of(static_cast<std::size_t>(node_count), -1);
  for (int node = 0; node < node_count; ++node) {
    auto& refs = references[static_cast<std::size_t>(node)];
    if (refs.empty()) continue;
    index_of[static_cast<std::size_t>(node)] = static_cast<int>(out.node_ids.size());
    out.node_ids.push_back(node);
    out.nodes.push_back({std::to_string(node), std::move(refs)});
  }
  if (out.node_ids.empty()) throw std::invalid_argument("the map keeps no representative to localise against");
  out.successors.resize(out.node_ids.size());
  for (const auto& [ends, count] : edges) {
    const int from = index_of[static_cast<std::size_t>(ends.first)];
    const int to = index_of[static_cast<std::size_t>(ends.second)];
    if (from >= 0 && to >= 0) out.successors[static_cast<std::size_t>(from)].push_back({to, static_cast<double>(count)});
  }
  return out;
}

void ParticleFilterTopologyStage::startLocalizing(const NodeLocalizerConfig& config) {
  localizer_ = std::make_unique<NodeLocalizer>(config, mapNodesOf(*filter_, views_));
  localized_places_ = 0;
  estimate_.place = -1;
  estimate_.node = -1;
  estimate_.probability = 0.0;
  estimate_.is_new = false;
  estimate_.alternatives.clear();
}

void ParticleFilterTopologyStage::observeFrame(const Fingerprint& fingerprint) {
  if (!localizer_) return;
  const NodeFix fix = localizer_->update(fingerprint, alternatives_);
  estimate_.node = fix.node;
  estimate_.probability = fix.probability;
  estimate_.is_new = false;
  estimate_.alternatives.clear();
  for (const NodeFix::Alternative& a : fix.alternatives) estimate_.alternatives.push_back({a.node, a.probability});
}

FinishedPlace ParticleFilterTopologyStage::localizePlace(ClosedPlace place) {
  localizer_->placeClosed(place.last_frame - place.first_frame + 1);
  FinishedPlace done{std::move(place), PlaceAssignment{}};
  const NodeFix fix = done.place.representative ? localizer_->localizeOnce(*done.place.representative) : NodeFix{};
  // Numbered after the map's observations, as a resumed run's places are, so that no place number of this
  // run names one of the map's; the map itself gains nothing.
  done.assignment.place = filter_->observationCount() + localized_places_++;
  done.place.place = done.assignment.place;
  done.assignment.node = fix.node;
  done.assignment.is_new = false;
  done.assignment.probability = fix.probability;
  estimate_.place = done.assignment.place;
  return done;
}

void ParticleFilterTopologyStage::enqueuePlace(ClosedPlace place) { queue_.push_back(std::move(place)); }

std::optional<FinishedPlace> ParticleFilterTopologyStage::advance(double budget_s) {
  if (localizer_) {
    if (queue_.empty()) return std::nullopt;
    FinishedPlace done = localizePlace(std::move(queue_.front()));
    queue_.pop_front();
    return done;
  }
  const double deadline = clock_.now() + budget_s;
  do {
    if (!filter_->stepInProgress()) {
      if (queue_.empty()) return std::nullopt;
      // Evidence by earlier place of this run -> by filter observation.
      // The place stays at the front of the queue until its step is done.
      const std::vector<double>& by_place = queue_.front().evidence;
      step_evidence_.assign(by_place.empty() ? 0 : static_cast<std::size_t>(run_first_observation_), 0.0);
      step_evidence_.insert(step_evidence_.end(), by_place.begin(), by_place.end());
      filter_->beginStep(queue_.front().representative, step_evidence_, queue_.front().samples);
    }
    if (filter_->advance(slice_items_)) {
      FinishedPlace done{std::move(queue_.front()), PlaceAssignment{}};
      queue_.pop_front();
      representative_frames_.push_back(done.place.representative_frame);
      views_.resize(static_cast<std::size_t>(filter_->observationCount() - 1));
      views_.push_back(std::move(done.place.views));  // the map's from now on; nothing later reads them
      if (spans_.empty() || done.place.first_frame > spans_.back().last_frame)
        spans_.push_back({done.place.first_frame, done.place.last_frame, filter_->observationCount() - 1});
      if (done.place.last_frame > last_mapped_frame_) {
        last_mapped_frame_ = done.place.last_frame;
        last_mapped_name_ = name_of_ ? name_of_(last_mapped_frame_) : std::string();
      }
      ++revision_;
      refresh();
      done.assignment.place = estimate_.place;
      done.assignment.node = estimate_.node;
      done.assignment.is_new = estimate_.is_new;
      done.assignment.probability = estimate_.probability;
      done.place.place = done.assignment.place;
      return done;
    }
  } while (clock_.now() < deadline);
  return std::nullopt;
}

void ParticleFilterTopologyStage::refresh() {
  const int observations = filter_->observationCount();
  PlaceEstimate e;
  e.map_revision = revision_;
  TopologySnapshot t;
  t.map_revision = revision_;
  t.particles = filter_->config().particles;
  best_assignment_.clear();
  if (observations > 0) {
    const TopologyEstimate te = filter_->estimate(alternatives_ + 1);
    const std::vector<int>& assignment = te.best.assignment;
    best_assignment_ = assignment;  // node of each observation, for locate()
    e.place = observations - 1;
    e.node = te.current_node;
    e.probability = te.current_node_probability;
    e.is_new = !assignment.empty() &&
               std::find(assignment.begin(), assignment.end() - 1, assignment.back()) == assignment.end() - 1;
    for (const LocationHypothesis& h : te.locations) {
      if (static_cast<int>(e.alternatives.size()) >= alternatives_) break;
      if (h.node_in_best == e.node && h.node_in_best >= 0) continue;  // the estimate itself
      e.alternatives.push_back({h.node_in_best, h.probability});
    }
    t.probability = te.best.probability;
    t.nodes.resize(static_cast<std::size_t>(te.best.node_count));
    for (int i = 0; i < te.best.node_count; ++i) t.nodes[static_cast<std::size_t>(i)].id = i;
    std::map<std::pair<int, int>, int> edges;
    for (std::size_t k = 0; k < assignment.size(); ++k) {
      const int node = assignment[k];
      if (node < 0 || node >= te.best.node_count) continue;
      TopologyNode& n = t.nodes[static_cast<std::size_t>(node)];
      n.places.push_back(static_cast<int>(k));
      n.representative_frames.push_back(k < representative_frames_.size() ? representative_frames_[k] : -1);
      if (k > 0 && assignment[k - 1] != node) ++edges[{assignment[k - 1], node}];
    }
    for (const auto& [ends, count] : edges) t.edges.push_back({ends.first, ends.second, count});
  }
  estimate_ = std::move(e);
  topology_ = std::move(t);
}

void ParticleFilterTopologyStage::locate(RevisitEstimate& r) const {
  r.match_place = -1;
  r.match_node = -1;
  if (localizer_) {  // localisation only: the node the robot is in now is the frame's own answer
    r.match_node = estimate_.node;
    return;
  }
  if (r.match_frame < 0) return;
  // The last span starting at or before the frame, if it reaches it.
  const auto it = std::upper_bound(spans_.begin(), spans_.end(), r.match_frame,
                                   [](std::int64_t f, const PlaceSpan& s) { return f < s.first_frame; });
  if (it == spans_.begin() || r.match_frame > std::prev(it)->last_frame) return;
  const int observation = std::prev(it)->observation;
  r.match_place = observation;
  if (observation >= 0 && static_cast<std::size_t>(observation) < best_assignment_.size())
    r.match_node = best_assignment_[static_cast<std::size_t>(observation)];
}

namespace {

/// The map as it was at one moment: the filter's frozen state (pointer copies, taken on the topology
/// thread) and the application data. Encoding it, which grows with the map, happens in writeTo(), on the
/// map writer thread, then MapStore's atomic replace (temporary file, fsync, rename).
class FrozenMap final : public MapSnapshot {
 public:
  FrozenMap(FrozenTopologyState state, std::string application_data, MapSettings settings, PlaceViews views)
      : state_(std::move(state)),
        application_data_(std::move(application_data)),
        settings_(std::move(settings)),
        views_(std::move(views)) {}
  void writeTo(const std::string& path) const override {
    const std::string bytes = MapStore::encode(state_, application_data_, settings_, views_);
    bytes_.store(bytes.size());
    MapStore::writeAtomically(path, bytes);
  }
  std::size_t bytes() const override { return bytes_.load(); }

 private:
  FrozenTopologyState state_;
  std::string application_data_;
  MapSettings settings_;
  PlaceViews views_;  ///< pointer copies: the views never change once stored
  mutable std::atomic<std::size_t> bytes_{0};
};

}  // namespace

std::unique_ptr<const MapSnapshot> ParticleFilterTopologyStage::snapshotMap() const {
  std::ostringstream data;
  data << "toposlamd-frames";
  for (std::int64_t f : representative_frames_) data << ' ' << f;
  MapSettings settings = map_settings_;
  // A name that would break the settings' "key=value" lines is not recorded (the source then starts over).
  if (last_mapped_frame_ >= 0 && !last_mapped_name_.empty() &&
      last_mapped_name_.find_first_of("\r\n") == std::string::npos) {
    settings[kMapSourceLastFrameKey] = std::to_string(last_mapped_frame_);
    settings[kMapSourceLastFrameNameKey] = last_mapped_name_;
  }
  return std::make_unique<FrozenMap>(filter_->freeze(), data.str(), std::move(settings), views_);
}

}  // namespace toposlam
