// OfflineMapper: fingerprint -> segment -> topology filter step, over consecutive traversals.
#include "toposlam/pipeline/offline_mapper.hpp"

#include <stdexcept>
#include <utility>

namespace toposlam {

namespace {

SegmentedPlace shifted(SegmentedPlace p, std::int64_t frame_offset, std::int64_t index_offset) {
  p.first_frame += frame_offset;
  p.last_frame += frame_offset;
  p.representative_frame += frame_offset;
  if (p.valley_frame >= 0) p.valley_frame += frame_offset;
  p.index += index_offset;
  return p;
}

}  // namespace

void appendSegmentationRun(SegmentationRun& all, const SegmentationRun& part) {
  const auto frame_offset = static_cast<std::int64_t>(all.frames.size());
  const auto kept_offset = static_cast<std::int64_t>(all.places.size());
  const auto dropped_offset = static_cast<std::int64_t>(all.dropped_places.size());
  for (SegmentationFrameRecord f : part.frames) {
    f.frame += frame_offset;
    if (f.place >= 0) f.place += kept_offset;
    all.frames.push_back(std::move(f));
  }
  for (const SegmentedPlace& p : part.places) {
    all.places.push_back(shifted(p, frame_offset, kept_offset));
    all.places.back().representative.reset();
  }
  for (const SegmentedPlace& p : part.dropped_places) {
    all.dropped_places.push_back(shifted(p, frame_offset, dropped_offset));
    all.dropped_places.back().representative.reset();
  }
}

OfflineMapper::OfflineMapper(const VpackExtractor& extractor, const SimilarityMeasure& similarity,
                             const FiedlerSegmenterConfig& config, TopologyParticleFilter& filter)
    : extractor_(extractor),
      similarity_(similarity),
      config_(config),
      filter_(filter),
      first_observation_(filter.observationCount()) {
  if (const std::string problem = config_.validate(); !problem.empty()) {
    throw std::invalid_argument("segmentation config: " + problem);
  }
}

void OfflineMapper::useSequenceEvidence(const SequenceEvidenceConfig& config) {
  if (!finished_.frames.empty() || current_) throw std::logic_error("OfflineMapper: sequence evidence after the first frame");
  evidence_ = config.weight > 0.0 ? std::make_unique<PlaceSequenceEvidence>(config, similarity_) : nullptr;
}

void OfflineMapper::beginTraversal() {
  if (current_) finish();
  if (evidence_) evidence_->beginTraversal();
  current_ = std::make_unique<OfflineSegmentation>(extractor_, similarity_, config_);
  ++traversal_count_;
}

std::shared_ptr<const Fingerprint> OfflineMapper::fingerprint(const cv::Mat& image) const {
  return std::make_shared<const Fingerprint>(extractor_.extract(image));
}

SegmentedPlace OfflineMapper::toRunNumbering(SegmentedPlace place) const {
  const auto frame_offset = static_cast<std::int64_t>(finished_.frames.size());
  const auto index_offset =
      static_cast<std::int64_t>(place.dropped ? finished_.dropped_places.size() : finished_.places.size());
  return shifted(std::move(place), frame_offset, index_offset);
}

SegmenterStep OfflineMapper::segment(double time_s, const std::string& name,
                                     std::shared_ptr<const Fingerprint> fingerprint, const MotionState& motion) {
  if (!current_) beginTraversal();
  const std::shared_ptr<const Fingerprint> for_evidence = evidence_ ? fingerprint : nullptr;
  SegmenterStep step = current_->segment(time_s, name, std::move(fingerprint), motion);
  step.frame += static_cast<std::int64_t>(finished_.frames.size());
  if (evidence_) evidence_->addFrame(step.frame, time_s, for_evidence);
  if (step.closed_place) step.closed_place = toRunNumbering(std::move(*step.closed_place));
  return step;
}

std::optional<MappedPlace> OfflineMapper::mapPlace(const SegmentedPlace& place) {
  if (place.dropped) return std::nullopt;
  if (!place.representative) throw std::invalid_argument("OfflineMapper::mapPlace: place without a representative");
  if (evidence_) {
    // Evidence by kept place of this run; the filter numbers observations from the map's first one.
    const std::vector<double> by_place = evidence_->closePlace(place.first_frame, place.last_frame);
    std::vector<double> by_observation(static_cast<std::size_t>(first_observation_), 0.0);
    by_observation.insert(by_observation.end(), by_place.begin(), by_place.end());
    filter_.step(place.representative, by_observation);
  } else {
    filter_.step(place.representative);
  }
  MappedPlace mapped{place, filter_.estimate(3)};
  mapped.place.representative.reset();  // the filter keeps what it needs
  steps_.push_back(mapped);
  return mapped;
}

std::optional<SegmentedPlace> OfflineMapper::finishTraversal() {
  if (!current_) return std::nullopt;
  std::optional<SegmentedPlace> last = current_->finish();
  if (last) last = toRunNumbering(std::move(*last));
  appendSegmentationRun(finished_, current_->run());
  current_.reset();
  return last;
}

void OfflineMapper::process(const cv::Mat& image, double time_s, const std::string& name) {
  const SegmenterStep step = segment(time_s, name, fingerprint(image));
  if (step.closed_place) mapPlace(*step.closed_place);
}

void OfflineMapper::finish() {
  if (std::optional<SegmentedPlace> last = finishTraversal()) mapPlace(*last);
}

SegmentationRun OfflineMapper::run() const {
  SegmentationRun all = finished_;
  if (current_) appendSegmentationRun(all, current_->run());
  return all;
}

std::vector<std::int64_t> OfflineMapper::placeNodes() const {
  const TopologyEstimate estimate = filter_.estimate(0);
  const std::vector<int>& assignment = estimate.best.assignment;
  std::vector<std::int64_t> nodes;
  for (std::size_t k = static_cast<std::size_t>(first_observation_); k < assignment.size(); ++k) {
    nodes.push_back(assignment[k]);
  }
  return nodes;
}

}  // namespace toposlam
