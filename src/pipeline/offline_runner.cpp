// OfflineRunner: the stage adapters driven in order on one thread, and the run's frame and place rows.
#include "toposlam/pipeline/offline_runner.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace toposlam {

OfflineRunner::OfflineRunner(FingerprintStage& fingerprint, FiedlerSegmentationStage& segmentation,
                             ParticleFilterTopologyStage* topology)
    : fingerprint_(fingerprint),
      segmentation_(segmentation),
      topology_(topology),
      first_observation_(topology != nullptr ? topology->observations() : 0) {}

void OfflineRunner::beginTraversal() {
  if (open_) finish();
  segmentation_.beginTraversal();
  ++traversal_count_;
  open_ = true;
}

std::shared_ptr<const Fingerprint> OfflineRunner::fingerprint(const cv::Mat& image, const cv::Mat& grey) {
  // The thumbnail, if the stage makes one, is for place events, which the offline commands do not publish.
  return std::make_shared<const Fingerprint>(fingerprint_.process(image, grey).fingerprint);
}

SegmenterStep OfflineRunner::segment(double source_time_s, const std::string& name,
                                     std::shared_ptr<const Fingerprint> fingerprint) {
  if (!open_) beginTraversal();
  SegmentationFrameRecord row;
  row.frame = static_cast<std::int64_t>(run_.frames.size());
  row.name = name;
  row.keypoints = fingerprint ? fingerprint->keypointCount() : 0;
  // The offline run has no pipeline clock: motion is looked up at the frame's own time, the motion file's.
  const bool localizing = topology_ != nullptr && topology_->localizing();
  std::shared_ptr<const Fingerprint> kept = localizing ? fingerprint : nullptr;
  SegmentationStep stage_step = segmentation_.process(row.frame, source_time_s, source_time_s, std::move(fingerprint), cv::Mat());
  row.time_s = segmentation_.lastFrameTimeS();
  SegmenterStep step;
  step.frame = row.frame;
  if (!std::isnan(stage_step.lambda2)) step.lambda2 = stage_step.lambda2;
  row.lambda2 = step.lambda2;
  run_.frames.push_back(std::move(row));
  revisits_.push_back(stage_step.revisit);
  pending_ = std::move(stage_step.closed);
  // toposlamd's topology thread steps a closed place before it answers for the frame that closed it.
  if (kept && pending_) unobserved_ = std::move(kept);
  else if (kept) observe(*kept);
  if (segmentation_.lastClosedPlace()) {
    step.closed_place = *segmentation_.lastClosedPlace();
    record(*step.closed_place);
  }
  return step;
}

std::optional<MappedPlace> OfflineRunner::mapPlace(const SegmentedPlace& place) {
  if (place.dropped || topology_ == nullptr) return std::nullopt;
  if (!pending_ || pending_->place != place.index)
    throw std::logic_error("OfflineRunner::mapPlace: not the kept place the segmentation closed last");
  topology_->enqueuePlace(std::move(*pending_));
  pending_.reset();
  while (!topology_->idle())
    if (std::optional<FinishedPlace> done = topology_->advance(std::numeric_limits<double>::infinity());
        done && topology_->localizing())
      localized_place_nodes_.push_back(done->assignment.node);
  if (unobserved_) {
    observe(*unobserved_);
    unobserved_.reset();
  }
  MappedPlace mapped{place, topology_->filter().estimate(3)};
  mapped.place.representative.reset();
  steps_.push_back(mapped);
  return mapped;
}

std::optional<SegmentedPlace> OfflineRunner::finishTraversal() {
  if (!open_) return std::nullopt;
  open_ = false;
  pending_ = segmentation_.finish();
  const std::optional<SegmentedPlace>& last = segmentation_.lastClosedPlace();
  if (last) record(*last);
  return last;
}

void OfflineRunner::process(const cv::Mat& image, double source_time_s, const std::string& name) {
  const SegmenterStep step = segment(source_time_s, name, fingerprint(image));
  if (step.closed_place) mapPlace(*step.closed_place);
}

void OfflineRunner::finish() {
  if (std::optional<SegmentedPlace> last = finishTraversal()) mapPlace(*last);
}

void OfflineRunner::observe(const Fingerprint& fingerprint) {
  topology_->observeFrame(fingerprint);
  frame_nodes_.push_back({topology_->estimate().node, topology_->estimate().probability});
}

void OfflineRunner::record(const SegmentedPlace& place) {
  const auto first = static_cast<std::size_t>(std::max<std::int64_t>(0, place.first_frame));
  const auto end = std::min(run_.frames.size(), static_cast<std::size_t>(place.last_frame + 1));
  for (std::size_t f = first; f < end; ++f) {
    run_.frames[f].place = place.dropped ? -1 : place.index;
    run_.frames[f].in_dropped_place = place.dropped;
  }
  (place.dropped ? run_.dropped_places : run_.places).push_back(place);
}

std::vector<std::int64_t> OfflineRunner::placeNodes() const {
  std::vector<std::int64_t> nodes;
  if (topology_ == nullptr) return nodes;
  if (topology_->localizing()) return localized_place_nodes_;
  // The topology stage's snapshot (the one toposlamd publishes) lists each node's places by observation.
  const TopologySnapshot best = topology_->topology();
  nodes.assign(static_cast<std::size_t>(topology_->observations() - first_observation_), -1);
  for (const TopologyNode& node : best.nodes) {
    for (const int observation : node.places) {
      if (observation >= first_observation_) nodes[static_cast<std::size_t>(observation - first_observation_)] = node.id;
    }
  }
  return nodes;
}

}  // namespace toposlam
