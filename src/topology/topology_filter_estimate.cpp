// TopologyParticleFilter's estimate: the distinct topologies the particles hold, the most probable one
// with its alternatives, where the robot is, and the sizes of the shared structures. See the header.
#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include "topology_state.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

using topology_detail::HistoryRecord;
using topology_detail::idx;
using topology_detail::TopologyState;
using topology_detail::TrieBranch;
using topology_detail::TrieNode;

namespace {

std::vector<int> assignmentOf(const TopologyState& state) {
  std::vector<int> out;
  for (const HistoryRecord* r = state.record.get(); r; r = r->parent.get()) out.push_back(r->node);
  std::reverse(out.begin(), out.end());
  return out;
}

void countTrieNodes(const TrieNode* node, int level, std::unordered_set<const TrieNode*>& seen) {
  if (!node || !seen.insert(node).second || level == 0) return;
  for (const auto& child : static_cast<const TrieBranch*>(node)->children)
    countTrieNodes(child.get(), level - 1, seen);
}

}  // namespace

std::vector<int> TopologyParticleFilter::particleAssignment(int i) const {
  return assignmentOf(*particles_.at(idx(i)));
}

TopologyEstimate TopologyParticleFilter::estimate(int alternatives) const {
  if (phase_ != Phase::Idle)
    throw std::logic_error("TopologyParticleFilter::estimate: a step is in progress");
  TopologyEstimate out;
  out.observations = observation_count_;
  out.effective_sample_size = last_ess_;
  const double m = static_cast<double>(particles_.size());
  // Distinct states in order of their first particle, with counts.
  std::vector<const TopologyState*> states;
  std::vector<int> counts;
  std::unordered_map<const TopologyState*, std::size_t> index;
  for (const auto& p : particles_) {
    auto [it, inserted] = index.emplace(p.get(), states.size());
    if (inserted) {
      states.push_back(p.get());
      counts.push_back(0);
    }
    ++counts[it->second];
  }
  out.distinct_topologies = static_cast<int>(states.size());
  std::vector<std::size_t> order(states.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return counts[a] > counts[b]; });

  auto describe = [&](std::size_t s) {
    TopologyHypothesis h;
    h.probability = counts[s] / m;
    h.node_count = states[s]->nodeCount();
    h.current_node = states[s]->currentNode();
    return h;
  };
  // The best topology's assignment: only the records since the one the memo (the last estimate's best)
  // shares with it are walked, usually the last step's. Walking all of them, one heap record per
  // observation, took milliseconds at 10,000 places.
  {
    std::vector<const HistoryRecord*> suffix;
    const HistoryRecord* r = states[order[0]]->record.get();
    for (; r && !(idx(r->observation) < estimate_records_.size() && estimate_records_[idx(r->observation)] == r);
         r = r->parent.get())
      suffix.push_back(r);
    const std::size_t shared = r ? idx(r->observation) + 1 : 0;
    estimate_records_.resize(shared);
    estimate_assignment_.resize(shared);
    for (auto it = suffix.rbegin(); it != suffix.rend(); ++it) {
      estimate_records_.push_back(*it);
      estimate_assignment_.push_back((*it)->node);
    }
    for (const auto& p : particles_)  // a shared_ptr of that state keeps the memo's records alive
      if (p.get() == states[order[0]]) estimate_state_ = p;
  }
  out.best = describe(order[0]);
  out.best.assignment = estimate_assignment_;
  for (std::size_t k = 1; k < order.size() && static_cast<int>(k) <= alternatives; ++k) {
    TopologyHypothesis h = describe(order[k]);
    // Its records since the last one it shares with the best topology; before that it is the best's.
    std::vector<const HistoryRecord*> suffix;
    const HistoryRecord* r = states[order[k]]->record.get();
    for (; r && !(idx(r->observation) < estimate_records_.size() && estimate_records_[idx(r->observation)] == r);
         r = r->parent.get())
      suffix.push_back(r);
    const std::size_t shared = r ? idx(r->observation) + 1 : 0;
    h.assignment.assign(estimate_assignment_.begin(), estimate_assignment_.begin() + static_cast<std::ptrdiff_t>(shared));
    for (auto it = suffix.rbegin(); it != suffix.rend(); ++it) h.assignment.push_back((*it)->node);
    for (std::size_t o = shared; o < h.assignment.size(); ++o) {
      if (h.assignment[o] != out.best.assignment[o]) {
        h.first_difference = static_cast<int>(o);
        break;
      }
    }
    out.alternatives.push_back(std::move(h));
  }
  out.current_node = out.best.current_node;
  if (observation_count_ == 0) return out;

  // Current-node hypotheses, identified by the first observation of the node.
  const TopologyState& best = *states[order[0]];
  // The best topology's node founded at observation `founder`, if any: the node it assigned that
  // observation to, when that node's first observation it is.
  const auto bestNodeOf = [&](int founder) {
    if (founder < 0 || idx(founder) >= out.best.assignment.size()) return -1;
    const int n = out.best.assignment[idx(founder)];
    return best.nodes.get(n).first_observation == founder ? n : -1;
  };
  std::vector<LocationHypothesis> locations;
  std::unordered_map<int, std::size_t> location_index;
  for (std::size_t s = 0; s < states.size(); ++s) {
    const int founder = states[s]->nodes.get(states[s]->currentNode()).first_observation;
    auto [it, inserted] = location_index.emplace(founder, locations.size());
    if (inserted) {
      LocationHypothesis l;
      l.founding_observation = founder;
      l.node_in_best = bestNodeOf(founder);
      locations.push_back(l);
    }
    locations[it->second].probability += counts[s] / m;
  }
  std::stable_sort(
      locations.begin(), locations.end(),
      [](const LocationHypothesis& a, const LocationHypothesis& b) { return a.probability > b.probability; });
  const int best_founder = best.nodes.get(best.currentNode()).first_observation;
  for (const auto& l : locations) {
    if (l.founding_observation == best_founder) out.current_node_probability = l.probability;
  }
  out.locations = std::move(locations);
  return out;
}

TopologyMemoryStats TopologyParticleFilter::memoryStats() const {
  TopologyMemoryStats stats;
  std::unordered_set<const TopologyState*> states;
  std::unordered_set<const HistoryRecord*> records;
  std::unordered_set<const TrieNode*> trie;
  for (const auto& p : particles_) {
    if (!states.insert(p.get()).second) continue;
    for (const HistoryRecord* r = p->record.get(); r && records.insert(r).second; r = r->parent.get()) {
    }
    countTrieNodes(p->nodes.root().get(), p->nodes.levels(), trie);
  }
  stats.distinct_states = states.size();
  stats.history_records = records.size();
  stats.trie_nodes = trie.size();
  for (const auto& f : fingerprints_) stats.stored_fingerprints += f ? 1 : 0;
  stats.candidate_index_bytes = index_ ? index_->bytes() : 0;
  return stats;
}

}  // namespace toposlam
