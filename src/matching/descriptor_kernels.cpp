// Brute-force nearest-neighbour kernels for keypoint descriptors: see descriptor_kernels.hpp.
#include "descriptor_kernels.hpp"

#include <bit>
#include <cstddef>
#include <cmath>
#include <limits>

// Hardware popcount when the build does not already assume it (x86-64 baseline has none): GCC and
// Clang emit a hardware and a portable clone and pick one through an ifunc resolver at load time.
#if defined(__x86_64__) && !defined(__POPCNT__) && defined(__has_attribute)
#if __has_attribute(target_clones)
#define TOPOSLAM_POPCOUNT_CLONES __attribute__((target_clones("popcnt", "default")))
#endif
#endif
#ifndef TOPOSLAM_POPCOUNT_CLONES
#define TOPOSLAM_POPCOUNT_CLONES
#endif

namespace toposlam::detail {
namespace {

// Updates (best, second, index) with one candidate distance. Ties keep the earlier row.
template <typename Distance>
[[gnu::always_inline]] inline void consider(Distance distance, int row, Distance& best, Distance& second,
                                            int& best_row) {
  if (distance < best) {
    second = best;
    best = distance;
    best_row = row;
  } else if (distance < second) {
    second = distance;
  }
}

// Best and second best reference row per query row. kWords > 0 fixes the row length at compile time
// (the inner loop unrolls to kWords XOR + popcount); kWords == 0 takes it from `words` at run time.
// With reference_best (and its scratch reference_best_distance, reference_count each), also the best
// query row of every reference row (ties: the earlier query row), from the same distances; with
// kReferenceSecond also its second best distance (reference_second_distance), so the pass answers the
// reverse direction in full.
template <int kWords, bool kReferenceSecond>
[[gnu::always_inline]] inline void scanBinary(const std::uint64_t* query, int query_count,
                                              const std::uint64_t* reference, int reference_count,
                                              int words, DescriptorMatch* out, int* reference_best,
                                              int* reference_best_distance, int* reference_second_distance) {
  const int row_words = kWords > 0 ? kWords : words;
  if (reference_best != nullptr) {
    for (int r = 0; r < reference_count; ++r) {
      reference_best[r] = -1;
      reference_best_distance[r] = std::numeric_limits<int>::max();
      if constexpr (kReferenceSecond) reference_second_distance[r] = std::numeric_limits<int>::max();
    }
  }
  for (int q = 0; q < query_count; ++q) {
    const std::uint64_t* qrow = query + static_cast<std::ptrdiff_t>(q) * row_words;
    int best = std::numeric_limits<int>::max();
    int second = std::numeric_limits<int>::max();
    int best_row = -1;
    for (int r = 0; r < reference_count; ++r) {
      const std::uint64_t* rrow = reference + static_cast<std::ptrdiff_t>(r) * row_words;
      int distance = 0;
      for (int w = 0; w < row_words; ++w) distance += std::popcount(qrow[w] ^ rrow[w]);
      consider(distance, r, best, second, best_row);
      if constexpr (kReferenceSecond) {
        // Query rows arrive in order, so this is consider() run over the reverse direction.
        consider(distance, q, reference_best_distance[r], reference_second_distance[r], reference_best[r]);
      } else if (reference_best != nullptr && distance < reference_best_distance[r]) {
        reference_best_distance[r] = distance;
        reference_best[r] = q;
      }
    }
    out[q].reference_keypoint = best_row;
    out[q].distance = static_cast<float>(best);
    out[q].second_distance = second == std::numeric_limits<int>::max()
                                 ? std::numeric_limits<float>::infinity()
                                 : static_cast<float>(second);
  }
}

template <bool kReferenceSecond>
[[gnu::always_inline]] inline void scanBinaryRows(const std::uint64_t* query, int query_count,
                                                  const std::uint64_t* reference, int reference_count, int words,
                                                  DescriptorMatch* out, int* reference_best,
                                                  int* reference_best_distance, int* reference_second_distance) {
  switch (words) {
    case 4:  // ORB, 32 bytes
      scanBinary<4, kReferenceSecond>(query, query_count, reference, reference_count, words, out, reference_best,
                                      reference_best_distance, reference_second_distance);
      break;
    case 8:  // BRISK (64 bytes), AKAZE-MLDB (61 bytes, padded)
      scanBinary<8, kReferenceSecond>(query, query_count, reference, reference_count, words, out, reference_best,
                                      reference_best_distance, reference_second_distance);
      break;
    default:
      scanBinary<0, kReferenceSecond>(query, query_count, reference, reference_count, words, out, reference_best,
                                      reference_best_distance, reference_second_distance);
      break;
  }
}

}  // namespace

TOPOSLAM_POPCOUNT_CLONES
void bestBinaryMatches(const std::uint64_t* query, int query_count, const std::uint64_t* reference,
                       int reference_count, int words, DescriptorMatch* out, int* reference_best,
                       int* reference_best_distance) {
  scanBinaryRows<false>(query, query_count, reference, reference_count, words, out, reference_best,
                        reference_best_distance, nullptr);
}

TOPOSLAM_POPCOUNT_CLONES
void bestBinaryMatchesBothWays(const std::uint64_t* query, int query_count, const std::uint64_t* reference,
                               int reference_count, int words, DescriptorMatch* out, DescriptorMatch* reverse_out,
                               int* reference_best, int* reference_best_distance, int* reference_second_distance) {
  scanBinaryRows<true>(query, query_count, reference, reference_count, words, out, reference_best,
                       reference_best_distance, reference_second_distance);
  for (int r = 0; r < reference_count; ++r) {
    reverse_out[r].reference_keypoint = reference_best[r];
    reverse_out[r].distance = static_cast<float>(reference_best_distance[r]);
    reverse_out[r].second_distance = reference_second_distance[r] == std::numeric_limits<int>::max()
                                         ? std::numeric_limits<float>::infinity()
                                         : static_cast<float>(reference_second_distance[r]);
  }
}

void bestFloatMatches(const float* query, int query_count, int query_stride, const float* reference,
                      int reference_count, int reference_stride, int dims, DescriptorMatch* out,
                      int* reference_best, float* reference_best_distance) {
  if (reference_best != nullptr) {
    for (int r = 0; r < reference_count; ++r) {
      reference_best[r] = -1;
      reference_best_distance[r] = std::numeric_limits<float>::infinity();
    }
  }
  for (int q = 0; q < query_count; ++q) {
    const float* qrow = query + static_cast<std::ptrdiff_t>(q) * query_stride;
    float best = std::numeric_limits<float>::infinity();
    float second = std::numeric_limits<float>::infinity();
    int best_row = -1;
    for (int r = 0; r < reference_count; ++r) {
      const float* rrow = reference + static_cast<std::ptrdiff_t>(r) * reference_stride;
      float squared = 0.f;
      for (int d = 0; d < dims; ++d) {
        const float difference = qrow[d] - rrow[d];
        squared += difference * difference;
      }
      consider(squared, r, best, second, best_row);
      if (reference_best != nullptr && squared < reference_best_distance[r]) {
        reference_best_distance[r] = squared;
        reference_best[r] = q;
      }
    }
    out[q].reference_keypoint = best_row;
    out[q].distance = std::sqrt(best);
    out[q].second_distance = std::sqrt(second);
  }
}

}  // namespace toposlam::detail
