// Fixed sizes of the topology filter's node entries: a node keeps at most this many successors and
// representatives per particle (TopologyFilterConfig's max_successors and max_representatives_per_node are
// bounded by them). A header of its own so the filter's private state can use them without the filter.
#pragma once

namespace toposlam {

/// Largest allowed max_successors and max_representatives_per_node (fixed-size node entries).
inline constexpr int kTopologyMaxSuccessors = 8;
inline constexpr int kTopologyMaxRepresentatives = 16;

}  // namespace toposlam
