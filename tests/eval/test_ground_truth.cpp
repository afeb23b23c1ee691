// Loop-closure ground truth of the data sets (src/eval/ground_truth.cpp): the bundled matrix and pairs
// file, and a clear error for a file that is no image.
#include <catch2/catch.hpp>

#include "eval_fixture.hpp"
#include "toposlam/eval/ground_truth.hpp"

using namespace toposlam::eval;
using namespace toposlam::eval::testing;
using Catch::Matchers::Contains;

SCENARIO(
    "GIVEN the bundled samples_GT.bmp and samples_GT_pairs.csv WHEN loaded THEN both hold the same 228 loop "
    "closures") {
  const std::string samples = TOPOSLAM_SAMPLES_DIR;
  const LoopClosureMatrix m = loadLoopClosureImage(samples + "/samples_GT.bmp");
  REQUIRE(m.size == 84);
  CHECK(m.at(40, 0));  // 41.jpg revisits 1.jpg
  CHECK(m.at(0, 40));  // symmetric after loading
  CHECK_FALSE(m.at(1, 0));
  CHECK(m.at(80, 38));  // 81.jpg - 39.jpg
  int marked = 0;
  for (int i = 0; i < 84; ++i) {
    for (int j = 0; j < i; ++j) marked += m.at(i, j) ? 1 : 0;
  }
  CHECK(marked == 228);
  const auto pairs = loadLoopClosurePairs(samples + "/samples_GT_pairs.csv");
  REQUIRE(pairs.size() == 228);
  CHECK(pairs[0].query == "41.jpg");
  CHECK(pairs[0].match == "1.jpg");
  CHECK(pairs[0].line == 2);
}

SCENARIO("GIVEN a loop-closure matrix file that is no image WHEN loaded THEN the error names the file") {
  const auto dir = scratchDir("bad-gt");
  writeText(dir / "gt.bmp", "not an image");
  CHECK_THROWS_WITH(loadLoopClosureImage((dir / "gt.bmp").string()),
                    Contains("gt.bmp: cannot read as an image"));
}
