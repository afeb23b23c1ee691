// Brute-force nearest-neighbour kernels for keypoint descriptors (private to toposlam_matching).
// Binary descriptors are packed into whole 64-bit words (zero padded) so the Hamming distance is a few
// XOR + popcount per pair; on x86-64 without -mpopcnt the kernel is compiled twice (hardware popcount
// and a portable fallback) and chosen once at load time, and on CPUs with AVX-512 VPOPCNTDQ a blocked,
// vectorised scan (word columns, eight rows per instruction) gives the same results. Float descriptors
// use squared L2.
//
// Thread-safety: pure functions.
#pragma once

#include <cstdint>

#include "toposlam/matching/ngram_matcher.hpp"

namespace toposlam::detail {

/// For each of query_count query rows (each `words` 64-bit words), the best and second best reference
/// rows by Hamming distance. out[q].reference_keypoint = -1 when reference_count == 0.
/// reference_best (optional, with reference_best_distance as scratch, reference_count each) receives the
/// best query row of every reference row (ties: the earlier query row), for the mutual check, computed
/// from the same distances.
void bestBinaryMatches(const std::uint64_t* query, int query_count, const std::uint64_t* reference,
                       int reference_count, int words, DescriptorMatch* out, int* reference_best = nullptr,
                       int* reference_best_distance = nullptr);

/// bestBinaryMatches with reference_best, and the whole reverse direction from the same distances:
/// reverse_out[r] (reference_count of them) is what bestBinaryMatches(reference, query) would give reference
/// row r, its best query row (ties: the earlier), that distance and the second best. reference_best,
/// reference_best_distance and reference_second_distance are reference_count each (the last two scratch).
/// One pass for both directions of a symmetric similarity.
void bestBinaryMatchesBothWays(const std::uint64_t* query, int query_count, const std::uint64_t* reference,
                               int reference_count, int words, DescriptorMatch* out, DescriptorMatch* reverse_out,
                               int* reference_best, int* reference_best_distance, int* reference_second_distance);

/// The vectorisable blocked scan that bestBinaryMatches and bestBinaryMatchesBothWays use on CPUs with
/// AVX-512 VPOPCNTDQ, here compiled for any CPU, so tests can check it equals the row-by-row scan
/// everywhere. reverse_out null: bestBinaryMatches; else bestBinaryMatchesBothWays (all scratch given).
void bestBinaryMatchesPortableBlocked(const std::uint64_t* query, int query_count, const std::uint64_t* reference,
                                      int reference_count, int words, DescriptorMatch* out, DescriptorMatch* reverse_out,
                                      int* reference_best = nullptr, int* reference_best_distance = nullptr,
                                      int* reference_second_distance = nullptr);

/// Same for float rows of `dims` values (row strides in floats); distances are L2 (not squared).
void bestFloatMatches(const float* query, int query_count, int query_stride, const float* reference,
                      int reference_count, int reference_stride, int dims, DescriptorMatch* out,
                      int* reference_best = nullptr, float* reference_best_distance = nullptr);

}  // namespace toposlam::detail
