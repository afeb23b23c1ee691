// A topology's node likelihoods over its shared node-table trie: see node_likelihoods.hpp.
#include "node_likelihoods.hpp"

namespace toposlam::topology_detail {

void markReferenced(const TrieNode* node, int level, std::uint64_t stamp, std::vector<unsigned char>& needed) {
  if (!node || node->visit_stamp == stamp) return;
  node->visit_stamp = stamp;
  if (level == 0) {
    for (const NodeEntry& entry : static_cast<const TrieLeaf*>(node)->entries) {
      for (int r = 0; r < entry.representative_count; ++r) needed[idx(entry.representatives[idx(r)])] = 1;
    }
    return;
  }
  for (const auto& child : static_cast<const TrieBranch*>(node)->children) {
    markReferenced(child.get(), level - 1, stamp, needed);
  }
}

void aggregateNodeLikelihoods(const TrieNode* node, int level, std::uint64_t stamp,
                              const std::vector<double>& similarity, LLogLMemo& l_log_l) {
  if (node->memo_stamp == stamp) return;
  double sum = 0.0, sum_l_log_l = 0.0, max = 0.0;
  if (level == 0) {
    for (const NodeEntry& entry : static_cast<const TrieLeaf*>(node)->entries) {
      if (entry.first_observation < 0) continue;
      const double l = entryLikelihood(entry, similarity);
      sum += l;
      sum_l_log_l += l_log_l(l);
      max = std::max(max, l);
    }
  } else {
    for (const auto& child : static_cast<const TrieBranch*>(node)->children) {
      if (!child) continue;
      aggregateNodeLikelihoods(child.get(), level - 1, stamp, similarity, l_log_l);
      sum += child->memo_sum;
      sum_l_log_l += child->memo_sum_l_log_l;
      max = std::max(max, child->memo_max);
    }
  }
  node->memo_sum = sum;
  node->memo_sum_l_log_l = sum_l_log_l;
  node->memo_max = max;
  node->memo_stamp = stamp;
}

}  // namespace toposlam::topology_detail
