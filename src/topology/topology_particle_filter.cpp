// TopologyParticleFilter's step machine: beginStep() sets a step up, advance() runs its phases in order
// within a work budget (collect, propose, compare, aggregate, resample, update: one file each for
// proposing, weighing, and resampling with the map update), finishStep() makes the new particles current.
// The estimate, the state's bytes and the models live in topology_filter_*.cpp. See the header and
// docs/topology.md.
#include "toposlam/topology/topology_particle_filter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "topology_state.hpp"

namespace toposlam {

using topology_detail::idx;
using topology_detail::TopologyState;

TopologyParticleFilter::TopologyParticleFilter(const TopologyFilterConfig& config,
                                               const SimilarityMeasure& similarity)
    : config_(config), similarity_(similarity) {
  if (const std::string problem = config_.validate(); !problem.empty()) throw std::invalid_argument(problem);
  rng_.seed(config_.seed);
  transition_ = knownNodeTransition(config_);
  particles_.assign(idx(config_.particles), std::make_shared<const TopologyState>());
}

TopologyParticleFilter::~TopologyParticleFilter() = default;

double TopologyParticleFilter::uniform01() {
  // 53 random bits -> [0, 1), identical on every platform (std distributions are not specified).
  return static_cast<double>(rng_() >> 11) * 0x1.0p-53;
}

void TopologyParticleFilter::beginStep(std::shared_ptr<const Fingerprint> representative,
                                       std::span<const double> evidence,
                                       std::span<const std::shared_ptr<const Fingerprint>> samples) {
  if (phase_ != Phase::Idle) throw std::logic_error("TopologyParticleFilter: a step is already in progress");
  if (!representative) throw std::invalid_argument("TopologyParticleFilter: null representative");
  if (evidence.size() > idx(observation_count_))
    throw std::invalid_argument("TopologyParticleFilter: evidence for " + std::to_string(evidence.size()) +
                                " observations, only " + std::to_string(observation_count_) + " made");
  evidence_.assign(evidence.begin(), evidence.end());
  for (double& e : evidence_) e = std::isfinite(e) ? std::clamp(e, 0.0, 1.0) : 0.0;
  if (observation_count_ == std::numeric_limits<std::int32_t>::max())
    throw std::length_error("too many observations");
  pending_ = std::move(representative);
  pending_samples_.clear();
  if (config_.likelihood == LikelihoodModel::Relative)
    for (const auto& sample : samples)
      if (sample) pending_samples_.push_back(sample);
  sample_similarity_.assign(pending_samples_.size() * idx(observation_count_), 0.0);
  ++stamp_;
  const std::size_t m = particles_.size();
  groups_.clear();
  group_of_.assign(m, 0);
  std::unordered_map<const TopologyState*, std::int32_t> group_index;
  for (std::size_t i = 0; i < m; ++i) {
    auto [it, inserted] = group_index.emplace(particles_[i].get(), static_cast<std::int32_t>(groups_.size()));
    if (inserted) groups_.push_back(particles_[i]);
    group_of_[i] = it->second;
  }
  needed_.assign(idx(observation_count_), 0);
  needed_list_.clear();
  similarity_of_.assign(idx(observation_count_), 0.0);
  group_stats_.assign(groups_.size(), GroupStats{});
  proposal_.assign(m, 0);
  weight_.assign(m, 0.0);
  chosen_.assign(m, 0);
  next_particles_.assign(m, nullptr);
  child_index_.clear();
  phase_ = Phase::Collect;
  cursor_ = 0;
}

bool TopologyParticleFilter::advance(std::size_t budget) {
  if (budget == 0) throw std::invalid_argument("TopologyParticleFilter::advance: budget must be >= 1");
  WorkBudget work{0, budget};
  while (phase_ != Phase::Idle) {
    bool finished = true;
    switch (phase_) {
      case Phase::Collect: finished = collectStored(work); break;
      case Phase::Propose: finished = proposeNodes(work); break;
      case Phase::Similarity: finished = compareWithStored(work); break;
      case Phase::Aggregate: finished = aggregatePerTopology(work); break;
      case Phase::Resample: finished = resample(work); break;
      case Phase::Update: finished = updateMap(work); break;
      case Phase::Idle: break;
    }
    if (!finished) return false;
  }
  return true;
}

void TopologyParticleFilter::finishStep() {
  if (index_) {
    index_->add(observation_count_, *pending_);
    indexable_.push_back(PlaceCandidateIndex::supports(*pending_) ? 1 : 0);
  }
  particles_.swap(next_particles_);
  next_particles_.clear();
  children_.clear();
  child_index_.clear();
  groups_.clear();
  fingerprints_.push_back(std::move(pending_));
  pending_.reset();
  pending_samples_.clear();
  ++observation_count_;
  phase_ = Phase::Idle;
  cursor_ = 0;
}

void TopologyParticleFilter::step(std::shared_ptr<const Fingerprint> representative, std::span<const double> evidence,
                                  std::span<const std::shared_ptr<const Fingerprint>> samples) {
  beginStep(std::move(representative), evidence, samples);
  while (!advance(std::numeric_limits<std::size_t>::max())) {
  }
}

std::unique_ptr<TopologyParticleFilter> TopologyParticleFilter::fork(const SimilarityMeasure& similarity) const {
  if (phase_ != Phase::Idle) throw std::logic_error("TopologyParticleFilter::fork: a step is in progress");
  auto copy = std::make_unique<TopologyParticleFilter>(config_, similarity);
  copy->rng_ = rng_;
  copy->observation_count_ = observation_count_;
  // Memo stamps the original will never reach: the copy's steps cannot pass for the original's.
  copy->stamp_ = stamp_ + (std::uint64_t{1} << 62);
  copy->fingerprints_ = fingerprints_;
  copy->particles_ = particles_;
  copy->last_ess_ = last_ess_;
  copy->degenerate_steps_ = degenerate_steps_;
  return copy;
}

void TopologyParticleFilter::setCandidateSelection(const CandidateSelectionConfig& candidates) {
  if (phase_ != Phase::Idle) throw std::logic_error("TopologyParticleFilter::setCandidateSelection: a step is in progress");
  if (const std::string problem = candidates.validate(); !problem.empty())
    throw std::invalid_argument("candidates." + problem);
  config_.candidates = candidates;
  index_.reset();
}

std::shared_ptr<const Fingerprint> TopologyParticleFilter::storedRepresentative(int observation) const {
  if (observation < 0 || idx(observation) >= fingerprints_.size()) return nullptr;
  return fingerprints_[idx(observation)];
}

}  // namespace toposlam
