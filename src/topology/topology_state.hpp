// Private to toposlam_topology: the shared, immutable data behind TopologyParticleFilter's particles.
//
// - HistoryRecord: one assignment (observation -> node) with a pointer to the previous one; particles
//   that agree on a prefix share it. Destruction of a long chain is iterative (no deep recursion).
// - NodeTable: a persistent vector of NodeEntry (a radix trie, 16 entries per level); setting one entry
//   copies only the O(log16 N) trie nodes on its path, the rest is shared with the parent state.
// - RecentNodes: the last max_successors + 1 distinct nodes visited, each with the successors seen since
//   it was last left (pending); a node leaving this list (or re-entered) commits its pending successors
//   to its NodeEntry. A node whose pending list is not full is always in this list (fewer than
//   max_successors distinct nodes were visited after it), so nothing is lost.
// - TopologyState: one distinct topology = record + node table + recent nodes.
//
// Trie nodes carry mutable per-step memo fields (the filter is single-threaded; see the filter header).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>

#include "toposlam/topology/topology_limits.hpp"

namespace toposlam::topology_detail {

/// A signed index or count as a container index.
inline std::size_t idx(std::int64_t i) { return static_cast<std::size_t>(i); }

inline constexpr int kTrieBits = 4;
inline constexpr int kTrieFanout = 1 << kTrieBits;

struct NodeEntry {
  std::int32_t first_observation = -1;  ///< -1: unused slot
  std::int32_t representative_count = 0;
  std::int32_t successor_count = 0;
  std::array<std::int32_t, kTopologyMaxRepresentatives> representatives{};  ///< oldest first
  std::array<std::int32_t, kTopologyMaxSuccessors> successors{};            ///< 1st successor first
};

class TrieNode {
 public:
  // Memo of the filter's step `memo_stamp` over the entries below this node.
  mutable std::uint64_t visit_stamp = 0;
  mutable std::uint64_t memo_stamp = 0;
  mutable double memo_sum = 0.0;          ///< sum of node likelihoods
  mutable double memo_sum_l_log_l = 0.0;  ///< sum of L log L
  mutable double memo_max = 0.0;          ///< max node likelihood
};

class TrieBranch : public TrieNode {
 public:
  std::array<std::shared_ptr<const TrieNode>, kTrieFanout> children;
};

class TrieLeaf : public TrieNode {
 public:
  std::array<NodeEntry, kTrieFanout> entries;
};

/// Persistent vector of NodeEntry. Copying it copies one pointer.
class NodeTable {
 public:
  int size() const { return size_; }
  int levels() const { return levels_; }  ///< 0: the root is a leaf
  const std::shared_ptr<const TrieNode>& root() const { return root_; }
  const NodeEntry& get(int index) const;
  /// A new table equal to this one with entry `index` (<= size()) replaced or appended.
  NodeTable with(int index, const NodeEntry& entry) const;

 private:
  std::shared_ptr<const TrieNode> root_;
  int levels_ = 0;
  int size_ = 0;
};

struct RecentNode {
  std::int32_t node = -1;
  std::int32_t pending_count = 0;
  std::array<std::int32_t, kTopologyMaxSuccessors> pending{};
};

struct RecentNodes {
  std::int32_t size = 0;
  std::array<RecentNode, kTopologyMaxSuccessors + 1> items{};  ///< items[0]: the current node
};

struct HistoryRecord {
  HistoryRecord(std::shared_ptr<const HistoryRecord> parent_record, std::int32_t observation_index,
                std::int32_t node_id)
      : parent(std::move(parent_record)), observation(observation_index), node(node_id) {}
  ~HistoryRecord();
  HistoryRecord(const HistoryRecord&) = delete;
  HistoryRecord& operator=(const HistoryRecord&) = delete;

  mutable std::shared_ptr<const HistoryRecord> parent;  ///< mutable only for iterative destruction
  std::int32_t observation = 0;
  std::int32_t node = 0;
};

struct TopologyState {
  std::shared_ptr<const HistoryRecord> record;  ///< null before the first observation
  NodeTable nodes;
  RecentNodes recent;
  int nodeCount() const { return nodes.size(); }
  int currentNode() const { return record ? record->node : -1; }
  int previousNode() const { return recent.size > 1 ? recent.items[1].node : -1; }
};

/// The state after assigning `observation` to `node` (node == nodeCount() creates a new node), keeping at
/// most `max_successors` successors and `max_representatives` representatives per node (the filter
/// config's max_successors and max_representatives_per_node).
std::shared_ptr<const TopologyState> extendState(const TopologyState& parent, std::int32_t observation,
                                                 std::int32_t node, int max_successors, int max_representatives);

}  // namespace toposlam::topology_detail
