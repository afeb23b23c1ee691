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

// The same results as scanBinary, computed so that a compiler can vectorise them: the reference rows
// (at most kBlockRows) are transposed into word columns, each query row's distances to all of them are
// computed in one branch-free loop (XOR + popcount over whole columns: with AVX-512 VPOPCNTDQ eight rows
// per instruction), the reverse direction is updated by selects over those distances, and the query
// row's best and second best are what consider() keeps (ties: the earlier row; second = the smallest
// value besides that one): each distance is keyed as distance x 256 + row, so the smallest key is the best
// distance at its first row, and the smallest of the other keys is the second best (two min reductions).
constexpr int kBlockRows = 128;
constexpr int kRowBits = 8;  // kBlockRows <= 2^kRowBits

template <int kWords, bool kReferenceSecond>
[[gnu::always_inline]] inline void scanBinaryBlocked(const std::uint64_t* query, int query_count,
                                                     const std::uint64_t* reference, int reference_count,
                                                     DescriptorMatch* out, int* reference_best,
                                                     int* reference_best_distance, int* reference_second_distance) {
  alignas(64) std::uint64_t columns[kWords][kBlockRows];
  alignas(64) int keys[kBlockRows];
  const int n = reference_count;
  for (int r = 0; r < n; ++r)
    for (int w = 0; w < kWords; ++w) columns[w][r] = reference[static_cast<std::ptrdiff_t>(r) * kWords + w];
  if (reference_best != nullptr) {
    for (int r = 0; r < n; ++r) {
      reference_best[r] = -1;
      reference_best_distance[r] = std::numeric_limits<int>::max();
      if constexpr (kReferenceSecond) reference_second_distance[r] = std::numeric_limits<int>::max();
    }
  }
  for (int q = 0; q < query_count; ++q) {
    const std::uint64_t* qrow = query + static_cast<std::ptrdiff_t>(q) * kWords;
    std::uint64_t qwords[kWords];
    for (int w = 0; w < kWords; ++w) qwords[w] = qrow[w];
    int best_key = std::numeric_limits<int>::max();
    for (int r = 0; r < n; ++r) {
      int distance = 0;
      for (int w = 0; w < kWords; ++w) distance += std::popcount(qwords[w] ^ columns[w][r]);
      const int key = (distance << kRowBits) | r;
      keys[r] = key;
      best_key = std::min(best_key, key);
    }
    if (reference_best != nullptr) {
      int* __restrict best_of = reference_best;
      int* __restrict best_distance_of = reference_best_distance;
      if constexpr (kReferenceSecond) {
        int* __restrict second_distance_of = reference_second_distance;
        for (int r = 0; r < n; ++r) {
          const int d = keys[r] >> kRowBits;
          const int best = best_distance_of[r];
          const int second = second_distance_of[r];
          const bool better = d < best;
          second_distance_of[r] = better ? best : (d < second ? d : second);
          best_distance_of[r] = better ? d : best;
          best_of[r] = better ? q : best_of[r];
        }
      } else {
        for (int r = 0; r < n; ++r) {
          const int d = keys[r] >> kRowBits;
          const bool better = d < best_distance_of[r];
          best_distance_of[r] = better ? d : best_distance_of[r];
          best_of[r] = better ? q : best_of[r];
        }
      }
    }
    keys[best_key & ((1 << kRowBits) - 1)] = std::numeric_limits<int>::max();  // the others' minimum next
    int second_key = std::numeric_limits<int>::max();
    for (int r = 0; r < n; ++r) second_key = std::min(second_key, keys[r]);
    out[q].reference_keypoint = best_key & ((1 << kRowBits) - 1);
    out[q].distance = static_cast<float>(best_key >> kRowBits);
    out[q].second_distance = second_key == std::numeric_limits<int>::max()
                                 ? std::numeric_limits<float>::infinity()
                                 : static_cast<float>(second_key >> kRowBits);
  }
}

/// Whether scanBinaryBlocked serves this shape (ORB's 4 or BRISK/AKAZE's 8 words, 1..kBlockRows rows).
bool blockedShape(int reference_count, int words) {
  return reference_count >= 1 && reference_count <= kBlockRows && (words == 4 || words == 8);
}

template <bool kReferenceSecond>
[[gnu::always_inline]] inline void scanBinaryRowsBlocked(const std::uint64_t* query, int query_count,
                                                         const std::uint64_t* reference, int reference_count, int words,
                                                         DescriptorMatch* out, int* reference_best,
                                                         int* reference_best_distance, int* reference_second_distance) {
  if (words == 4) {
    scanBinaryBlocked<4, kReferenceSecond>(query, query_count, reference, reference_count, out, reference_best,
                                           reference_best_distance, reference_second_distance);
  } else {
    scanBinaryBlocked<8, kReferenceSecond>(query, query_count, reference, reference_count, out, reference_best,
                                           reference_best_distance, reference_second_distance);
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

// The blocked scan compiled for AVX-512 VPOPCNTDQ (x86-64 with GCC or Clang), chosen at run time when the
// CPU has it (about 2.5 times faster on 100 x 100 ORB rows); elsewhere the row-by-row scan, whose branches
// suit scalar popcount better.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define TOPOSLAM_HAVE_VPOPCNT_KERNEL 1
[[gnu::target("avx512f,avx512vpopcntdq")]] void scanBinaryVpopcnt(
    const std::uint64_t* query, int query_count, const std::uint64_t* reference, int reference_count, int words,
    DescriptorMatch* out, int* reference_best, int* reference_best_distance, int* reference_second_distance) {
  if (reference_second_distance != nullptr) {
    scanBinaryRowsBlocked<true>(query, query_count, reference, reference_count, words, out, reference_best,
                                reference_best_distance, reference_second_distance);
  } else {
    scanBinaryRowsBlocked<false>(query, query_count, reference, reference_count, words, out, reference_best,
                                 reference_best_distance, nullptr);
  }
}

bool cpuHasVpopcnt() {
  static const bool has = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vpopcntdq");
  return has;
}
#endif

/// True when the AVX-512 scan took the call.
bool scanBinaryFast(const std::uint64_t* query, int query_count, const std::uint64_t* reference, int reference_count,
                    int words, DescriptorMatch* out, int* reference_best, int* reference_best_distance,
                    int* reference_second_distance) {
#ifdef TOPOSLAM_HAVE_VPOPCNT_KERNEL
  if (blockedShape(reference_count, words) && cpuHasVpopcnt()) {
    scanBinaryVpopcnt(query, query_count, reference, reference_count, words, out, reference_best,
                      reference_best_distance, reference_second_distance);
    return true;
  }
#else
  (void)query, (void)query_count, (void)reference, (void)reference_count, (void)words, (void)out;
  (void)reference_best, (void)reference_best_distance, (void)reference_second_distance;
#endif
  return false;
}

void fillReverse(int reference_count, DescriptorMatch* reverse_out, const int* reference_best,
                 const int* reference_best_distance, const int* reference_second_distance) {
  for (int r = 0; r < reference_count; ++r) {
    reverse_out[r].reference_keypoint = reference_best[r];
    reverse_out[r].distance = static_cast<float>(reference_best_distance[r]);
    reverse_out[r].second_distance = reference_second_distance[r] == std::numeric_limits<int>::max()
                                         ? std::numeric_limits<float>::infinity()
                                         : static_cast<float>(reference_second_distance[r]);
  }
}

}  // namespace

TOPOSLAM_POPCOUNT_CLONES
void bestBinaryMatches(const std::uint64_t* query, int query_count, const std::uint64_t* reference,
                       int reference_count, int words, DescriptorMatch* out, int* reference_best,
                       int* reference_best_distance) {
  if (scanBinaryFast(query, query_count, reference, reference_count, words, out, reference_best,
                     reference_best_distance, nullptr))
    return;
  scanBinaryRows<false>(query, query_count, reference, reference_count, words, out, reference_best,
                        reference_best_distance, nullptr);
}

TOPOSLAM_POPCOUNT_CLONES
void bestBinaryMatchesBothWays(const std::uint64_t* query, int query_count, const std::uint64_t* reference,
                               int reference_count, int words, DescriptorMatch* out, DescriptorMatch* reverse_out,
                               int* reference_best, int* reference_best_distance, int* reference_second_distance) {
  if (!scanBinaryFast(query, query_count, reference, reference_count, words, out, reference_best,
                      reference_best_distance, reference_second_distance)) {
    scanBinaryRows<true>(query, query_count, reference, reference_count, words, out, reference_best,
                         reference_best_distance, reference_second_distance);
  }
  fillReverse(reference_count, reverse_out, reference_best, reference_best_distance, reference_second_distance);
}

TOPOSLAM_POPCOUNT_CLONES
void bestBinaryMatchesPortableBlocked(const std::uint64_t* query, int query_count, const std::uint64_t* reference,
                                      int reference_count, int words, DescriptorMatch* out, DescriptorMatch* reverse_out,
                                      int* reference_best, int* reference_best_distance,
                                      int* reference_second_distance) {
  const bool both = reverse_out != nullptr;
  if (!blockedShape(reference_count, words)) {
    if (both) {
      scanBinaryRows<true>(query, query_count, reference, reference_count, words, out, reference_best,
                           reference_best_distance, reference_second_distance);
    } else {
      scanBinaryRows<false>(query, query_count, reference, reference_count, words, out, reference_best,
                            reference_best_distance, nullptr);
    }
  } else if (both) {
    scanBinaryRowsBlocked<true>(query, query_count, reference, reference_count, words, out, reference_best,
                                reference_best_distance, reference_second_distance);
  } else {
    scanBinaryRowsBlocked<false>(query, query_count, reference, reference_count, words, out, reference_best,
                                 reference_best_distance, nullptr);
  }
  if (both) fillReverse(reference_count, reverse_out, reference_best, reference_best_distance, reference_second_distance);
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
