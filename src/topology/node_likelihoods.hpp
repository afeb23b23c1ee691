// Private to toposlam_topology: a topology's node likelihoods, read off its node table (see
// topology_state.hpp) for TopologyParticleFilter's weighing step.
//
// A known node's appearance likelihood is the largest similarity (or likelihood) of the representatives
// the topology gave it; a new node's depends on the sum and the entropy of all of them (eq. 5.6/5.7).
// aggregateNodeLikelihoods() memoises those sums per trie node and step, so particles that share part of
// a node table sum it once. markReferenced() finds which stored representatives some table still
// refers to (the ones a step compares with).
//
// Thread-safety: the memo fields live in the shared trie nodes; one filter, one thread.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "topology_state.hpp"

namespace toposlam::topology_detail {

/// eta from S1 = sum L, S2 = sum L log L over n known nodes: sum p log p = S2 / S1 - log S1.
inline double entropyFromSums(double sum, double sum_l_log_l, int n) {
  if (n <= 1 || !(sum > 0.0)) return 1.0;
  const double eta = -(sum_l_log_l / sum - std::log(sum)) / std::log(static_cast<double>(n));
  return std::clamp(eta, 0.0, 1.0);
}

inline double lLogL(double l) { return l > 0.0 ? l * std::log(l) : 0.0; }

/// lLogL that remembers its last argument: on an indexed step most nodes have the one background
/// likelihood, so the logarithm is taken once for all of them (same value, bit for bit).
struct LLogLMemo {
  double l = std::numeric_limits<double>::quiet_NaN();
  double l_log_l = 0.0;
  double operator()(double value) {
    if (value != l) {
      l = value;
      l_log_l = lLogL(value);
    }
    return l_log_l;
  }
};

/// A known node's likelihood: the max over its representatives of `similarity` (per observation).
inline double entryLikelihood(const NodeEntry& entry, const std::vector<double>& similarity) {
  double best = 0.0;
  for (int r = 0; r < entry.representative_count; ++r) {
    best = std::max(best, similarity[idx(entry.representatives[idx(r)])]);
  }
  return best;
}

/// Marks the observations referenced below `node` (each shared trie node once per stamp).
void markReferenced(const TrieNode* node, int level, std::uint64_t stamp, std::vector<unsigned char>& needed);

/// Sums of node likelihoods below `node` into its memo fields (memo_sum, memo_sum_l_log_l, memo_max),
/// memoised per stamp (shared subtrees are summed once).
void aggregateNodeLikelihoods(const TrieNode* node, int level, std::uint64_t stamp,
                              const std::vector<double>& similarity, LLogLMemo& l_log_l);

}  // namespace toposlam::topology_detail
