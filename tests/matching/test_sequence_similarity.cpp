// Sequence matching (sequence_similarity.hpp): the mean along the diagonal that ends at each cell, over
// candidate cells only, computed by hand on small matrices.
#include <catch2/catch.hpp>

#include <stdexcept>

#include "toposlam/matching/sequence_similarity.hpp"

using toposlam::sequenceSimilarity;

SCENARIO("GIVEN a 3 x 3 matrix WHEN sequences of 2 and 3 frames are scored THEN each cell is its diagonal's mean", "[sequence]") {
  const std::vector<float> s{0.1f, 0.2f, 0.3f,   //
                             0.4f, 0.5f, 0.6f,   //
                             0.7f, 0.8f, 0.9f};
  const std::vector<std::uint8_t> all(9, 1);
  const auto two = sequenceSimilarity(s, all, 3, 3, 2);
  CHECK(two[0] == Approx(0.1));               // (0,0): nothing before it
  CHECK(two[4] == Approx((0.5 + 0.1) / 2));   // (1,1) with (0,0)
  CHECK(two[5] == Approx((0.6 + 0.2) / 2));   // (1,2) with (0,1)
  CHECK(two[7] == Approx((0.8 + 0.4) / 2));   // (2,1) with (1,0)
  CHECK(two[6] == Approx(0.7));               // (2,0): its diagonal leaves the matrix
  const auto three = sequenceSimilarity(s, all, 3, 3, 3);
  CHECK(three[8] == Approx((0.9 + 0.5 + 0.1) / 3));
  CHECK(three[8] != Approx(two[8]));
}

SCENARIO("GIVEN non-candidate cells WHEN sequences are scored THEN they are left out of the mean and stay 0", "[sequence]") {
  const std::vector<float> s{0.9f, 0.0f,  //
                             0.0f, 0.3f};
  const std::vector<std::uint8_t> mask{0, 1,  //
                                       1, 1};
  const auto out = sequenceSimilarity(s, mask, 2, 2, 2);
  CHECK(out[0] == 0.f);                 // no candidate: stays 0 whatever its input
  CHECK(out[3] == Approx(0.3));         // (1,1): (0,0) is no candidate, so only itself
}

SCENARIO("GIVEN length 1 WHEN scored THEN the candidate cells are unchanged", "[sequence]") {
  const std::vector<float> s{0.25f, 0.5f, 0.75f, 1.0f, 0.125f, 0.0625f};
  const std::vector<std::uint8_t> all(6, 1);
  CHECK(sequenceSimilarity(s, all, 2, 3, 1) == s);
}

SCENARIO("GIVEN bad arguments WHEN scored THEN it says what is wrong", "[sequence]") {
  const std::vector<float> s(4, 0.f);
  const std::vector<std::uint8_t> all(4, 1);
  CHECK_THROWS_AS(sequenceSimilarity(s, all, 2, 2, 0), std::invalid_argument);
  CHECK_THROWS_AS(sequenceSimilarity(s, all, 2, 3, 2), std::invalid_argument);
  CHECK_THROWS_AS(sequenceSimilarity(s, std::vector<std::uint8_t>(3, 1), 2, 2, 2), std::invalid_argument);
}
