// FrameSimilarityMemo: the newest frame's symmetric similarities are computed once per earlier frame,
// only between beginFrame() and endFrame(), and are the wrapped measure's values.
#include <catch2/catch.hpp>

#include "toposlam/matching/frame_similarity_memo.hpp"

using namespace toposlam;

namespace {

/// Similarity by image width (a stand-in for content), counting its calls.
class CountingMeasure : public SimilarityMeasure {
 public:
  mutable int calls = 0;
  double similarity(const Fingerprint& reference, const Fingerprint& query) const override {
    ++calls;
    return 1.0 / (1.0 + std::abs(reference.image_width - 2 * query.image_width));
  }
};

Fingerprint ofWidth(int width) {
  Fingerprint f;
  f.image_width = width;
  return f;
}

}  // namespace

TEST_CASE("GIVEN a frame begun WHEN an earlier frame is compared with the newest twice THEN it is computed once, "
          "to the wrapped measure's value") {
  const CountingMeasure measure;
  FrameSimilarityMemo memo(measure);
  const Fingerprint earlier = ofWidth(10), other = ofWidth(7), newest = ofWidth(4);
  const double expected = measure.symmetricSimilarity(earlier, newest);
  measure.calls = 0;
  memo.beginFrame(&newest);
  CHECK(memo.symmetricSimilarity(earlier, newest) == expected);
  CHECK(measure.calls == 2);  // both directions
  CHECK(memo.symmetricSimilarity(earlier, newest) == expected);
  CHECK(measure.calls == 2);
  CHECK(memo.symmetricSimilarity(other, newest) == measure.symmetricSimilarity(other, newest));
  CHECK(memo.computed() == 2);
  CHECK(memo.remembered() == 1);
}

TEST_CASE("GIVEN the memo WHEN a pair does not end with the newest frame, or no frame is begun THEN it is "
          "computed every time") {
  const CountingMeasure measure;
  FrameSimilarityMemo memo(measure);
  const Fingerprint a = ofWidth(10), b = ofWidth(7), newest = ofWidth(4);
  memo.beginFrame(&newest);
  memo.symmetricSimilarity(newest, a);  // the newest first: not remembered
  memo.symmetricSimilarity(newest, a);
  memo.symmetricSimilarity(a, b);  // neither is the newest
  memo.symmetricSimilarity(a, b);
  memo.similarity(a, newest);  // one direction: passed through
  CHECK(measure.calls == 9);
  CHECK(memo.remembered() == 0);
  memo.endFrame();
  memo.symmetricSimilarity(a, newest);
  memo.symmetricSimilarity(a, newest);
  CHECK(memo.remembered() == 0);
  CHECK(measure.calls == 13);
}

TEST_CASE("GIVEN a frame ended WHEN the next frame is begun THEN nothing of the frame before is remembered") {
  const CountingMeasure measure;
  FrameSimilarityMemo memo(measure);
  const Fingerprint a = ofWidth(10), first = ofWidth(4), second = ofWidth(5);
  memo.beginFrame(&first);
  const double with_first = memo.symmetricSimilarity(a, first);
  memo.endFrame();
  memo.beginFrame(&second);
  const double with_second = memo.symmetricSimilarity(a, second);
  CHECK(with_second == measure.symmetricSimilarity(a, second));
  CHECK(with_second != with_first);
  CHECK(memo.remembered() == 0);
}
