// Sequence matching: a query frame and a reference frame are scored by how well the stretch of route
// that ends at them matches, not by the two frames alone (SeqSLAM, Milford and Wyeth 2012; the corridor
// set's own paper, Milford 2013, shows it is what makes low-resolution frames recognisable). The score of
// (query q, reference r) is the mean frame similarity of the pairs (q - k, r - k), k = 0 .. length - 1:
// the robot retracing the reference route at the speed it was recorded. Only earlier frames are used,
// so the score of a new frame is ready the moment it arrives (the online setting). Pairs that are no
// candidate (mask 0, or off the matrix) are left out of the mean; a cell that is no candidate keeps 0.
//
// Measured on the bundled real sets (docs/matching.md, "Sequences"): it lifts both our similarity and the
// ORB baseline, and speed changes between the traversals (searched as SeqSLAM does) cost more than they
// bring, so the diagonal is the only one.
//
// Pure function; thread-safe.
#pragma once

#include <cstdint>
#include <vector>

namespace toposlam {

/// similarity and candidate: queries x references, row-major. length >= 1 (1 returns the candidate cells
/// unchanged). Throws std::invalid_argument on a size mismatch or length < 1.
std::vector<float> sequenceSimilarity(const std::vector<float>& similarity, const std::vector<std::uint8_t>& candidate,
                                      int queries, int references, int length);

}  // namespace toposlam
