// TopologyParticleFilter's first phases: which stored representatives the particles still refer to
// (collect), and step 1, each particle's next node drawn from the transition model (propose): eq. 5.8
// from a node never left yet, else "stay", the successors and a new node with knownNodeTransition's
// weights. See the header and docs/topology.md.
#include <algorithm>

#include "node_likelihoods.hpp"
#include "topology_state.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

using topology_detail::idx;
using topology_detail::markReferenced;
using topology_detail::NodeEntry;
using topology_detail::TopologyState;

bool TopologyParticleFilter::collectStored(WorkBudget& work) {
  for (; cursor_ < groups_.size(); ++cursor_) {
    if (!work.take()) return false;
    const TopologyState& g = *groups_[cursor_];
    markReferenced(g.nodes.root().get(), g.nodes.levels(), stamp_, needed_);
  }
  for (std::size_t o = 0; o < needed_.size(); ++o) {
    if (needed_[o]) {
      needed_list_.push_back(static_cast<std::int32_t>(o));
    } else if (fingerprints_[o]) {
      if (index_) index_->remove(static_cast<int>(o), *fingerprints_[o]);
      fingerprints_[o].reset();  // no particle refers to it any more: forget it
    }
  }
  phase_ = Phase::Propose;
  cursor_ = 0;
  return true;
}

bool TopologyParticleFilter::proposeNodes(WorkBudget& work) {
  const std::size_t m = particles_.size();
  for (; cursor_ < m; ++cursor_) {
    if (!work.take()) return false;
    const auto g = idx(group_of_[cursor_]);
    const TopologyState& state = *groups_[g];
    const int n = state.nodeCount();
    std::int32_t next = n;  // new node unless chosen otherwise
    if (n > 0) {
      const int current = state.currentNode();
      const NodeEntry& entry = state.nodes.get(current);
      if (entry.successor_count == 0) {
        // No adjacency information (never left this node): eq. 5.8.
        const double u = uniform01() * (n + config_.alpha);
        if (u < n) next = std::min(static_cast<std::int32_t>(u), static_cast<std::int32_t>(n - 1));
      } else {
        const double u = uniform01();
        double cumulative = transition_.stay;
        if (u < cumulative) {
          next = current;
        } else {
          const int previous = state.previousNode();
          std::size_t rank = 0;
          for (int s = 0; s < entry.successor_count && rank < transition_.successor.size(); ++s) {
            const std::int32_t candidate = entry.successors[idx(s)];
            if (config_.forbid_return_to_previous && candidate == previous) continue;
            cumulative += transition_.successor[rank++];
            if (u < cumulative) {
              next = candidate;
              break;
            }
          }
        }
      }
    }
    proposal_[cursor_] = next;
  }
  selectComparisons();
  phase_ = Phase::Similarity;
  cursor_ = 0;
  return true;
}

}  // namespace toposlam
