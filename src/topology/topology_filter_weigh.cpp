// TopologyParticleFilter's weighing phases (steps 2 and 3): which stored representatives the new one is
// compared with (all of them, or the candidate index's picks plus a background sample on large maps),
// the comparisons themselves, their conversion into appearance likelihoods (absolute, relative, with the
// place's samples, raised by outside evidence), the per-topology aggregates a new node's likelihood
// needs, and each particle's weight. See the header and docs/topology.md.
#include <algorithm>
#include <cmath>
#include <limits>

#include "node_likelihoods.hpp"
#include "topology_state.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

using topology_detail::entropyFromSums;
using topology_detail::entryLikelihood;
using topology_detail::idx;
using topology_detail::LLogLMemo;
using topology_detail::NodeEntry;
using topology_detail::TopologyState;
using topology_detail::TrieNode;

void TopologyParticleFilter::selectComparisons() {
  // needed_ marks: 1 = stored, 2 = compared (candidate or not indexable), 3 = compared (background sample).
  indexed_step_ = false;
  background_extra_sq_ = 0.0;
  const CandidateSelectionConfig& c = config_.candidates;
  if (needed_list_.size() <= idx(c.exhaustive_up_to) || !PlaceCandidateIndex::supports(*pending_)) {
    compared_list_ = needed_list_;
    return;
  }
  if (!index_) {
    index_ = std::make_unique<PlaceCandidateIndex>(c.index);
    indexable_.assign(fingerprints_.size(), 0);
    for (std::size_t o = 0; o < fingerprints_.size(); ++o) {
      if (!fingerprints_[o]) continue;
      index_->add(static_cast<int>(o), *fingerprints_[o]);
      indexable_[o] = PlaceCandidateIndex::supports(*fingerprints_[o]) ? 1 : 0;
    }
  }
  indexed_step_ = true;
  ++indexed_steps_;
  for (const int o : index_->candidates(*pending_, c.candidates)) needed_[idx(o)] = 2;
  // The known nodes the particles propose: their likelihoods are the particles' weights, so they are
  // compared exactly whatever the index says (the proposals do not depend on the similarities).
  for (std::size_t i = 0; i < proposal_.size(); ++i) {
    const TopologyState& state = *groups_[idx(group_of_[i])];
    if (proposal_[i] >= state.nodeCount()) continue;
    const NodeEntry& entry = state.nodes.get(proposal_[i]);
    for (int r = 0; r < entry.representative_count; ++r) needed_[idx(entry.representatives[idx(r)])] = 2;
  }
  std::size_t rest = 0;
  for (const std::int32_t o : needed_list_) {
    if (needed_[idx(o)] != 1) continue;
    if (indexable_[idx(o)]) {
      ++rest;
    } else {
      needed_[idx(o)] = 2;  // the index cannot hold it: always compared
    }
  }
  const std::size_t samples = std::min(rest, idx(c.background_samples));
  std::size_t seen = 0, next_sample = 0, taken = 0;
  for (const std::int32_t o : needed_list_) {
    if (needed_[idx(o)] != 1) continue;
    // Evenly spread: the i-th sample is the (i * rest / samples)-th of the rest, in observation order.
    if (taken < samples && seen == next_sample) {
      needed_[idx(o)] = 3;
      ++taken;
      next_sample = taken * rest / samples;
    }
    ++seen;
  }
  compared_list_.clear();
  for (const std::int32_t o : needed_list_)
    if (needed_[idx(o)] >= 2) compared_list_.push_back(o);
}

void TopologyParticleFilter::fillBackground() {
  double sum = 0.0, sum_sq = 0.0;
  std::size_t samples = 0, filled = 0;
  for (const std::int32_t o : compared_list_) {
    if (needed_[idx(o)] != 3) continue;
    const double s = similarity_of_[idx(o)];
    sum += s;
    sum_sq += s * s;
    ++samples;
  }
  const double mean = samples > 0 ? sum / static_cast<double>(samples) : 0.0;
  const double variance = samples > 0 ? std::max(0.0, sum_sq / static_cast<double>(samples) - mean * mean) : 0.0;
  for (const std::int32_t o : needed_list_) {
    if (needed_[idx(o)] != 1) continue;
    similarity_of_[idx(o)] = mean;
    ++filled;
  }
  background_extra_sq_ = static_cast<double>(filled) * variance;
}

bool TopologyParticleFilter::compareWithStored(WorkBudget& work) {
  // The representative's comparisons, then each sample's: one work item each.
  const std::size_t compared = compared_list_.size();
  for (; cursor_ < compared * (1 + pending_samples_.size()); ++cursor_) {
    if (!work.take()) return false;
    const std::size_t pass = cursor_ / compared;
    const auto o = idx(compared_list_[cursor_ % compared]);
    const Fingerprint& query = pass == 0 ? *pending_ : *pending_samples_[pass - 1];
    const double s = similarity_.similarity(*fingerprints_[o], query);
    const double value = std::isfinite(s) ? std::clamp(s, 0.0, 1.0) : 0.0;
    if (pass == 0) {
      similarity_of_[o] = value;
    } else {
      sample_similarity_[(pass - 1) * similarity_of_.size() + o] = value;
    }
  }
  if (indexed_step_) fillBackground();
  if (config_.likelihood == LikelihoodModel::Relative) {
    if (pending_samples_.empty()) {
      relativeLikelihoods();
    } else {
      relativeLikelihoodsWithSamples();
    }
  }
  if (!evidence_.empty())
    for (const std::int32_t o : needed_list_)
      if (idx(o) < evidence_.size()) similarity_of_[idx(o)] = std::max(similarity_of_[idx(o)], evidence_[idx(o)]);
  phase_ = Phase::Aggregate;
  cursor_ = 0;
  return true;
}

void TopologyParticleFilter::relativeLikelihoods() {
  // Leave-one-out: each stored representative against the others this step compares with. Sums in
  // observation order, so the result does not depend on how the step was sliced.
  double sum = 0.0, sum_sq = 0.0;
  for (const std::int32_t o : needed_list_) {
    const double s = similarity_of_[idx(o)];
    sum += s;
    sum_sq += s * s;
  }
  sum_sq += background_extra_sq_;  // 0 unless indexed: the spread the background values stand for
  const int others = static_cast<int>(needed_list_.size()) - 1;
  // On an indexed step most values are the background's one: the same input gives the same likelihood,
  // so it is computed once for them (an exp per stored representative otherwise).
  double last_in = std::numeric_limits<double>::quiet_NaN(), last_out = 0.0;
  for (const std::int32_t o : needed_list_) {
    double& s = similarity_of_[idx(o)];
    if (s != last_in) {
      last_in = s;
      last_out = relativeLikelihood(s, sum - s, sum_sq - s * s, others, config_.relative_slope,
                                    config_.relative_offset, config_.relative_sigma_floor);
    }
    s = last_out;
  }
}

void TopologyParticleFilter::relativeLikelihoodsWithSamples() {
  // Each sample's similarities become relative likelihoods exactly as the representative's do (an
  // indexed step fills the uncompared ones with that sample's own background); a stored
  // representative keeps the best of them. Its likelihood is then sqrt(l_rep * max(l_rep, l_best)):
  // a sample can raise it, never lower it, and a single sample matching alone cannot reach 1.
  const std::size_t n = similarity_of_.size();
  representative_similarity_ = similarity_of_;
  best_sample_likelihood_.assign(n, 0.0);
  for (std::size_t k = 0; k < pending_samples_.size(); ++k) {
    for (const std::int32_t o : compared_list_) similarity_of_[idx(o)] = sample_similarity_[k * n + idx(o)];
    if (indexed_step_) fillBackground();
    relativeLikelihoods();
    for (const std::int32_t o : needed_list_)
      best_sample_likelihood_[idx(o)] = std::max(best_sample_likelihood_[idx(o)], similarity_of_[idx(o)]);
  }
  similarity_of_ = representative_similarity_;
  if (indexed_step_) fillBackground();
  relativeLikelihoods();
  for (const std::int32_t o : needed_list_) {
    double& l = similarity_of_[idx(o)];
    l = std::sqrt(l * std::max(l, best_sample_likelihood_[idx(o)]));
  }
}

bool TopologyParticleFilter::aggregatePerTopology(WorkBudget& work) {
  LLogLMemo l_log_l_memo;
  for (; cursor_ < groups_.size(); ++cursor_) {
    if (!work.take()) return false;
    const TopologyState& g = *groups_[cursor_];
    GroupStats& stats = group_stats_[cursor_];
    if (g.nodeCount() == 0) continue;  // first observation: nothing known
    topology_detail::aggregateNodeLikelihoods(g.nodes.root().get(), g.nodes.levels(), stamp_, similarity_of_,
                                              l_log_l_memo);
    const TrieNode& root = *g.nodes.root();
    stats.max = root.memo_max;
    const double eta = config_.new_node_entropy
                           ? entropyFromSums(root.memo_sum, root.memo_sum_l_log_l, g.nodeCount())
                           : 1.0;
    stats.new_likelihood = std::max(eta * (1.0 - stats.max), config_.new_node_likelihood_floor);
  }
  phase_ = Phase::Resample;
  cursor_ = 0;
  return true;
}

void TopologyParticleFilter::weighProposals() {
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    const auto g = idx(group_of_[i]);
    const TopologyState& state = *groups_[g];
    weight_[i] = proposal_[i] == state.nodeCount() ? group_stats_[g].new_likelihood
                                                   : entryLikelihood(state.nodes.get(proposal_[i]), similarity_of_);
  }
}

}  // namespace toposlam
