// TopologyParticleFilter's last phases: step 4, systematic resampling of the weighed proposals, and step 5,
// the map update: each chosen particle's state extended by its proposal, one child state per distinct
// (parent state, node), so particles that agree on the whole assignment share it. See the header and
// docs/topology.md.
#include <algorithm>
#include <cmath>

#include "topology_state.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

using topology_detail::idx;

bool TopologyParticleFilter::resample(WorkBudget& work) {
  if (!work.take()) return false;
  const std::size_t m = particles_.size();
  weighProposals();
  double total = 0.0, total_sq = 0.0;
  for (double w : weight_) {
    total += w;
    total_sq += w * w;
  }
  if (!(total > 0.0) || !std::isfinite(total)) {
    std::fill(weight_.begin(), weight_.end(), 1.0);
    total = static_cast<double>(m);
    total_sq = total;
    ++degenerate_steps_;
  }
  last_ess_ = total * total / total_sq;
  // Systematic resampling: one uniform offset, M evenly spaced pointers.
  const double spacing = total / static_cast<double>(m);
  double pointer = uniform01() * spacing;
  std::size_t i = 0;
  double cumulative = weight_[0];
  for (std::size_t j = 0; j < m; ++j) {
    while (cumulative <= pointer && i + 1 < m) cumulative += weight_[++i];
    chosen_[j] = static_cast<std::int32_t>(i);
    pointer += spacing;
  }
  phase_ = Phase::Update;
  cursor_ = 0;
  return true;
}

bool TopologyParticleFilter::updateMap(WorkBudget& work) {
  for (; cursor_ < particles_.size(); ++cursor_) {
    if (!work.take()) return false;
    const auto source = idx(chosen_[cursor_]);
    const auto g = static_cast<std::uint64_t>(group_of_[source]);
    const auto node = static_cast<std::uint64_t>(proposal_[source]);
    const std::uint64_t key = (g << 32) | node;
    auto [it, inserted] = child_index_.emplace(key, static_cast<std::int32_t>(children_.size()));
    if (inserted) {
      children_.push_back(topology_detail::extendState(*groups_[idx(g)], observation_count_, proposal_[source],
                                                       config_.max_successors,
                                                       config_.max_representatives_per_node));
    }
    next_particles_[cursor_] = children_[idx(it->second)];
  }
  finishStep();
  return true;
}

}  // namespace toposlam
