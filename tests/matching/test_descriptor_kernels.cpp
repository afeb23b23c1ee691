// Tests of the binary nearest-neighbour kernels (src/matching/descriptor_kernels.hpp): the dispatched
// kernel (on a CPU with AVX-512 VPOPCNTDQ the blocked, vectorised scan) and the blocked scan compiled for
// any CPU give exactly what a plain loop over all pairs gives: best and second best distance, the best
// row with ties to the earlier row, and the reverse direction, on rows drawn so that distances tie often.
#include <catch2/catch.hpp>

#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "descriptor_kernels.hpp"

using namespace toposlam;

namespace {

struct Naive {
  std::vector<DescriptorMatch> forward, reverse;
};

int distanceOf(const std::uint64_t* a, const std::uint64_t* b, int words) {
  int d = 0;
  for (int w = 0; w < words; ++w) d += __builtin_popcountll(a[w] ^ b[w]);
  return d;
}

/// best / second best of row `row` of `from` among all rows of `to`, ties to the earlier row.
DescriptorMatch naiveBest(const std::vector<std::uint64_t>& from, int row, const std::vector<std::uint64_t>& to,
                          int to_count, int words) {
  DescriptorMatch m;
  m.reference_keypoint = -1;
  int best = std::numeric_limits<int>::max(), second = std::numeric_limits<int>::max();
  for (int r = 0; r < to_count; ++r) {
    const int d = distanceOf(&from[static_cast<std::size_t>(row * words)], &to[static_cast<std::size_t>(r * words)], words);
    if (d < best) {
      second = best;
      best = d;
      m.reference_keypoint = r;
    } else if (d < second) {
      second = d;
    }
  }
  m.distance = static_cast<float>(best);
  m.second_distance = second == std::numeric_limits<int>::max() ? std::numeric_limits<float>::infinity()
                                                                 : static_cast<float>(second);
  return m;
}

/// Rows from a pool of 6 with 0-3 bits flipped: many equal distances.
std::vector<std::uint64_t> tiedRows(int rows, int words, std::mt19937_64& rng) {
  std::vector<std::uint64_t> pool(static_cast<std::size_t>(6 * words));
  for (auto& w : pool) w = rng();
  std::vector<std::uint64_t> out(static_cast<std::size_t>(rows * words));
  for (int r = 0; r < rows; ++r) {
    const auto base = static_cast<std::size_t>(static_cast<int>(rng() % 6) * words);
    for (int w = 0; w < words; ++w) out[static_cast<std::size_t>(r * words + w)] = pool[base + static_cast<std::size_t>(w)];
    for (int f = static_cast<int>(rng() % 4); f > 0; --f) {
      const auto bit = rng() % static_cast<std::uint64_t>(64 * words);
      out[static_cast<std::size_t>(r * words) + bit / 64] ^= std::uint64_t{1} << (bit % 64);
    }
  }
  return out;
}

void requireSame(const DescriptorMatch& got, const DescriptorMatch& want) {
  REQUIRE(got.reference_keypoint == want.reference_keypoint);
  REQUIRE(got.distance == want.distance);
  REQUIRE(got.second_distance == want.second_distance);
}

}  // namespace

SCENARIO("GIVEN binary rows with many ties WHEN matched by the dispatched and the blocked kernels THEN both equal a "
         "plain loop over all pairs, both ways") {
  std::mt19937_64 rng(11);
  int cases = 0;
  for (int words : {4, 8, 5}) {
    for (int reference_count : {1, 2, 7, 100, 128, 129, 200}) {
      for (int query_count : {1, 3, 100}) {
        const auto query = tiedRows(query_count, words, rng);
        const auto reference = tiedRows(reference_count, words, rng);
        std::vector<DescriptorMatch> want(static_cast<std::size_t>(query_count));
        std::vector<DescriptorMatch> want_reverse(static_cast<std::size_t>(reference_count));
        for (int q = 0; q < query_count; ++q) want[static_cast<std::size_t>(q)] = naiveBest(query, q, reference, reference_count, words);
        for (int r = 0; r < reference_count; ++r)
          want_reverse[static_cast<std::size_t>(r)] = naiveBest(reference, r, query, query_count, words);
        const auto n = static_cast<std::size_t>(reference_count);
        for (int kernel = 0; kernel < 2; ++kernel) {
          CAPTURE(words, reference_count, query_count, kernel);
          // One way, with the mutual check's reference_best.
          std::vector<DescriptorMatch> out(static_cast<std::size_t>(query_count));
          std::vector<int> best(n), best_distance(n), second_distance(n);
          if (kernel == 0) {
            detail::bestBinaryMatches(query.data(), query_count, reference.data(), reference_count, words, out.data(),
                                      best.data(), best_distance.data());
          } else {
            detail::bestBinaryMatchesPortableBlocked(query.data(), query_count, reference.data(), reference_count, words,
                                                     out.data(), nullptr, best.data(), best_distance.data());
          }
          for (int q = 0; q < query_count; ++q) requireSame(out[static_cast<std::size_t>(q)], want[static_cast<std::size_t>(q)]);
          for (int r = 0; r < reference_count; ++r) {
            REQUIRE(best[static_cast<std::size_t>(r)] == want_reverse[static_cast<std::size_t>(r)].reference_keypoint);
            REQUIRE(static_cast<float>(best_distance[static_cast<std::size_t>(r)]) ==
                    want_reverse[static_cast<std::size_t>(r)].distance);
          }
          // Both ways.
          std::vector<DescriptorMatch> forward(static_cast<std::size_t>(query_count)), reverse(n);
          if (kernel == 0) {
            detail::bestBinaryMatchesBothWays(query.data(), query_count, reference.data(), reference_count, words,
                                              forward.data(), reverse.data(), best.data(), best_distance.data(),
                                              second_distance.data());
          } else {
            detail::bestBinaryMatchesPortableBlocked(query.data(), query_count, reference.data(), reference_count,
                                                     words, forward.data(), reverse.data(), best.data(),
                                                     best_distance.data(), second_distance.data());
          }
          for (int q = 0; q < query_count; ++q)
            requireSame(forward[static_cast<std::size_t>(q)], want[static_cast<std::size_t>(q)]);
          for (int r = 0; r < reference_count; ++r)
            requireSame(reverse[static_cast<std::size_t>(r)], want_reverse[static_cast<std::size_t>(r)]);
          ++cases;
        }
      }
    }
  }
  CHECK(cases == 3 * 7 * 3 * 2);
}
