// Persistent node tables, history records and the state update (map update + successor bookkeeping)
// shared by TopologyParticleFilter's particles. See topology_state.hpp.
#include "topology_state.hpp"

#include <cassert>
#include <utility>

namespace toposlam::topology_detail {

HistoryRecord::~HistoryRecord() {
  // Unlink the chain iteratively: a lineage thousands of steps long would otherwise be destroyed by
  // recursion as deep as the chain.
  std::shared_ptr<const HistoryRecord> next = std::move(parent);
  while (next && next.use_count() == 1) {
    std::shared_ptr<const HistoryRecord> after = std::move(next->parent);
    next = std::move(after);  // destroys the old `next`, whose parent is now empty
  }
}

const NodeEntry& NodeTable::get(int index) const {
  assert(index >= 0 && index < size_);
  const TrieNode* node = root_.get();
  for (int level = levels_; level > 0; --level) {
    const int slot = (index >> (kTrieBits * level)) & (kTrieFanout - 1);
    node = static_cast<const TrieBranch*>(node)->children[static_cast<std::size_t>(slot)].get();
  }
  return static_cast<const TrieLeaf*>(node)->entries[static_cast<std::size_t>(index & (kTrieFanout - 1))];
}

namespace {

std::shared_ptr<const TrieNode> setIn(const TrieNode* node, int level, int index, const NodeEntry& entry) {
  const auto slot = static_cast<std::size_t>((index >> (kTrieBits * level)) & (kTrieFanout - 1));
  if (level == 0) {
    auto leaf =
        node ? std::make_shared<TrieLeaf>(*static_cast<const TrieLeaf*>(node)) : std::make_shared<TrieLeaf>();
    leaf->visit_stamp = 0;  // new content: forget the memo copied from the original
    leaf->memo_stamp = 0;
    leaf->entries[slot] = entry;
    return leaf;
  }
  auto branch = node ? std::make_shared<TrieBranch>(*static_cast<const TrieBranch*>(node))
                     : std::make_shared<TrieBranch>();
  branch->visit_stamp = 0;
  branch->memo_stamp = 0;
  branch->children[slot] = setIn(branch->children[slot].get(), level - 1, index, entry);
  return branch;
}

}  // namespace

NodeTable NodeTable::with(int index, const NodeEntry& entry) const {
  assert(index >= 0 && index <= size_);
  NodeTable result = *this;
  if (!result.root_) result.root_ = std::make_shared<TrieLeaf>();
  // Grow a level when the index does not fit: the old root becomes child 0 of a new branch.
  while (index >= (1 << (kTrieBits * (result.levels_ + 1)))) {
    auto branch = std::make_shared<TrieBranch>();
    branch->children[0] = result.root_;
    result.root_ = std::move(branch);
    ++result.levels_;
  }
  result.root_ = setIn(result.root_.get(), result.levels_, index, entry);
  if (index == size_) ++result.size_;
  return result;
}

namespace {

/// successors := pending followed by the old successors not in it, without `self`, at most `cap`.
void commitSuccessors(NodeEntry& entry, const RecentNode& recent, std::int32_t self, int cap) {
  std::array<std::int32_t, kTopologyMaxSuccessors> merged{};
  int count = 0;
  auto add = [&](std::int32_t node) {
    if (node == self || count >= cap) return;
    for (int i = 0; i < count; ++i) {
      if (merged[static_cast<std::size_t>(i)] == node) return;
    }
    merged[static_cast<std::size_t>(count++)] = node;
  };
  for (int i = 0; i < recent.pending_count; ++i) add(recent.pending[static_cast<std::size_t>(i)]);
  for (int i = 0; i < entry.successor_count; ++i) add(entry.successors[static_cast<std::size_t>(i)]);
  entry.successors = merged;
  entry.successor_count = count;
}

}  // namespace

std::shared_ptr<const TopologyState> extendState(const TopologyState& parent, std::int32_t observation,
                                                 std::int32_t node, int max_successors, int max_representatives) {
  assert(node >= 0 && node <= parent.nodeCount());
  auto child = std::make_shared<TopologyState>();
  child->record = std::make_shared<const HistoryRecord>(parent.record, observation, node);
  child->recent = parent.recent;
  NodeTable table = parent.nodes;
  const int cap_successors = max_successors;
  const int cap_representatives = max_representatives;

  NodeEntry entry;
  if (node == parent.nodeCount()) {
    entry.first_observation = observation;
  } else {
    entry = table.get(node);
  }
  // Map update: append the representative, dropping the oldest past the cap.
  if (entry.representative_count >= cap_representatives) {
    for (int i = 1; i < entry.representative_count; ++i) {
      entry.representatives[static_cast<std::size_t>(i - 1)] =
          entry.representatives[static_cast<std::size_t>(i)];
    }
    --entry.representative_count;
  }
  entry.representatives[static_cast<std::size_t>(entry.representative_count++)] = observation;

  RecentNodes& recent = child->recent;
  if (node != parent.currentNode()) {
    // Moving to `node`: it is a new successor of every recently visited node that still collects.
    int position = -1;
    for (int i = 0; i < recent.size; ++i) {
      RecentNode& item = recent.items[static_cast<std::size_t>(i)];
      if (item.node == node) {
        position = i;
        continue;
      }
      if (item.pending_count >= cap_successors) continue;
      bool present = false;
      for (int p = 0; p < item.pending_count; ++p)
        present = present || item.pending[static_cast<std::size_t>(p)] == node;
      if (!present) item.pending[static_cast<std::size_t>(item.pending_count++)] = node;
    }
    if (position >= 0) {
      // Re-entered while still recent: its path since it was left is complete.
      commitSuccessors(entry, recent.items[static_cast<std::size_t>(position)], node, cap_successors);
      for (int i = position; i > 0; --i)
        recent.items[static_cast<std::size_t>(i)] = recent.items[static_cast<std::size_t>(i - 1)];
    } else {
      if (recent.size == cap_successors + 1) {
        // The least recent node leaves the list; max_successors distinct nodes followed it, so its
        // pending list is full: commit it.
        const RecentNode& evicted = recent.items[static_cast<std::size_t>(recent.size - 1)];
        NodeEntry evicted_entry = table.get(evicted.node);
        commitSuccessors(evicted_entry, evicted, evicted.node, cap_successors);
        table = table.with(evicted.node, evicted_entry);
        --recent.size;
      }
      for (int i = recent.size; i > 0; --i)
        recent.items[static_cast<std::size_t>(i)] = recent.items[static_cast<std::size_t>(i - 1)];
      ++recent.size;
    }
    recent.items[0] = RecentNode{};
    recent.items[0].node = node;
  }
  child->nodes = table.with(node, entry);
  return child;
}

}  // namespace toposlam::topology_detail
