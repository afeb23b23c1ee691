// Tests of the n-gram matching engine, similarity and localiser on hand-built fingerprints
// (thesis Figure 3.9 worked example, Hamming on any row length, degenerate localisation cases).
#include <catch2/catch.hpp>

#include <random>

#include <opencv2/core.hpp>

#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/matching/place_localizer.hpp"

using namespace toposlam;

namespace {

cv::Mat randomRows(int rows, int bytes, std::mt19937_64& rng) {
  cv::Mat m(rows, bytes, CV_8U);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < bytes; ++c) m.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(rng() & 0xFF);
  return m;
}

HclHistogramBins oneHot(int bin) {
  HclHistogramBins h{};
  h[static_cast<std::size_t>(bin)] = 1.f;
  return h;
}

// Histogram at Hellinger distance d from oneHot(bin): mass a at `bin`, 1 - a at bin 12, sqrt(a) = 1 - d^2.
HclHistogramBins atDistance(int bin, double d) {
  const double rho = 1.0 - d * d;
  HclHistogramBins h{};
  h[static_cast<std::size_t>(bin)] = static_cast<float>(rho * rho);
  h[12] = static_cast<float>(1.0 - rho * rho);
  return h;
}

// Builds a fingerprint from per-letter histograms and descriptor blocks (one block per letter).
Fingerprint makeFingerprint(const std::vector<HclHistogramBins>& histograms, const std::vector<cv::Mat>& blocks) {
  Fingerprint f;
  f.image_width = 10 * static_cast<int>(histograms.size());
  f.image_height = 10;
  int row = 0;
  std::vector<cv::Mat> nonEmpty;
  for (std::size_t i = 0; i < histograms.size(); ++i) {
    Subregion s;
    s.column_begin = 10 * static_cast<int>(i);
    s.column_end = s.column_begin + 10;
    s.histogram = histograms[i];
    s.keypoint_begin = row;
    row += blocks[i].rows;
    s.keypoint_end = row;
    f.subregions.push_back(s);
    if (i > 0) f.edge_columns.push_back(s.column_begin);
    for (int k = 0; k < blocks[i].rows; ++k) f.keypoints.emplace_back(cv::Point2f(s.column_begin + 1.f, 5.f), 7.f);
    if (!blocks[i].empty()) nonEmpty.push_back(blocks[i]);
  }
  if (!nonEmpty.empty()) cv::vconcat(nonEmpty, f.descriptors);
  return f;
}

// Figure 3.9: reference letters R1, R2, R3 correspond to query letters Q0, Q1, Q2; R0, R4, Q3, Q4 match nothing.
struct Figure39 {
  Fingerprint reference;
  Fingerprint query;
  Figure39() {
    std::mt19937_64 rng(39);
    std::vector<cv::Mat> ref_blocks = {randomRows(3, 32, rng), randomRows(4, 32, rng), randomRows(2, 32, rng),
                                       randomRows(5, 32, rng), randomRows(2, 32, rng)};
    reference = makeFingerprint({oneHot(5), atDistance(0, 0.2), atDistance(1, 0.15), atDistance(2, 0.2), oneHot(6)},
                                ref_blocks);
    cv::Mat q0, q1, q2;
    cv::vconcat(std::vector<cv::Mat>{ref_blocks[1].rowRange(0, 2), randomRows(1, 32, rng)}, q0);  // 2 of 4
    q1 = ref_blocks[2].clone();                                                                  // 2 of 2
    cv::vconcat(std::vector<cv::Mat>{ref_blocks[3].rowRange(1, 4), randomRows(2, 32, rng)}, q2);  // 3 of 5
    query = makeFingerprint({oneHot(0), oneHot(1), oneHot(2), oneHot(3), oneHot(4)},
                            {q0, q1, q2, randomRows(3, 32, rng), randomRows(2, 32, rng)});
  }
};

}  // namespace

SCENARIO("Figure 3.9: three unigrams, two bigrams and one trigram for both feature types") {
  GIVEN("the worked example with histogram scores 0.8, 0.85, 0.8 and keypoint scores 2/4, 2/2, 3/5") {
    Figure39 example;
    REQUIRE(example.reference.validate().empty());
    REQUIRE(example.query.validate().empty());
    NgramMatcher matcher;
    WHEN("the query is counted against the reference") {
      const NgramCounts c = matcher.counts(example.reference, example.query);
      THEN("the histogram counts are 2.45, 1.65 ('1.65 effective bigrams out of two') and 0.8167") {
        CHECK(c.histogram_matched == std::array<int, 3>{3, 2, 1});
        CHECK(c.histogram[0] == Approx(2.45).epsilon(1e-6));
        CHECK(c.histogram[1] == Approx(1.65).epsilon(1e-6));
        CHECK(c.histogram[2] == Approx(2.45 / 3).epsilon(1e-6));
        CHECK(c.histogram_possible == std::array<int, 3>{5, 4, 3});
      }
      THEN("the keypoint counts are 2.1, 1.55 and 0.7") {
        CHECK(c.keypoint_matched == std::array<int, 3>{3, 2, 1});
        CHECK(c.keypoint[0] == Approx(2.1).epsilon(1e-6));
        CHECK(c.keypoint[1] == Approx(1.55).epsilon(1e-6));
        CHECK(c.keypoint[2] == Approx(0.7).epsilon(1e-6));
        CHECK(c.keypoint_possible == std::array<int, 3>{5, 4, 3});
        CHECK(c.matched_keypoints == 7);
      }
    }
    WHEN("the correspondences are listed") {
      const LetterCorrespondences l = matcher.correspondences(example.reference, example.query);
      THEN("they link R1-Q0, R2-Q1, R3-Q2 for both feature types") {
        REQUIRE(l.histogram.size() == 3);
        REQUIRE(l.keypoint.size() == 3);
        for (int t = 0; t < 3; ++t) {
          CHECK(l.histogram[t].reference_letter == t + 1);
          CHECK(l.histogram[t].query_letter == t);
          CHECK(l.keypoint[t].reference_letter == t + 1);
          CHECK(l.keypoint[t].query_letter == t);
        }
      }
    }
    WHEN("the query letters are reversed") {
      Figure39 reversed;
      Fingerprint& q = reversed.query;
      // Rebuild with letters in reverse order (descriptor blocks move with their letters).
      std::vector<HclHistogramBins> h;
      std::vector<cv::Mat> blocks;
      for (int i = static_cast<int>(q.subregions.size()) - 1; i >= 0; --i) {
        const Subregion& s = q.subregions[static_cast<std::size_t>(i)];
        h.push_back(s.histogram);
        blocks.push_back(q.descriptors.rowRange(s.keypoint_begin, s.keypoint_end).clone());
      }
      const NgramCounts c = NgramMatcher().counts(example.reference, makeFingerprint(h, blocks));
      THEN("unigrams are unchanged, bigrams and trigrams vanish") {
        CHECK(c.histogram[0] == Approx(2.45).epsilon(1e-6));
        CHECK(c.keypoint[0] == Approx(2.1).epsilon(1e-6));
        CHECK(c.histogram[1] == 0.0);
        CHECK(c.histogram[2] == 0.0);
        CHECK(c.keypoint[1] == 0.0);
        CHECK(c.keypoint[2] == 0.0);
      }
    }
  }
}

SCENARIO("Equally good candidates resolve to the order-consistent letter") {
  GIVEN("four letters with the same histogram and the same two descriptors, then a distinct fifth") {
    std::mt19937_64 rng(4);
    const cv::Mat block = randomRows(2, 32, rng);
    const Fingerprint f = makeFingerprint({oneHot(3), oneHot(3), oneHot(3), oneHot(3), oneHot(7)},
                                          {block, block, block, block, randomRows(2, 32, rng)});
    REQUIRE(f.validate().empty());
    WHEN("the fingerprint is counted against itself") {
      const NgramCounts c = NgramMatcher().counts(f, f);
      THEN("every letter pairs with itself: all 5 unigrams, 4 bigrams and 3 trigrams count fully") {
        // Ties to the leftmost letter and earliest keypoint gave histogram counts 5, 0, 0 and keypoint 2, 0, 0.
        CHECK(c.histogram[0] == Approx(5.0));
        CHECK(c.histogram[1] == Approx(4.0));
        CHECK(c.histogram[2] == Approx(3.0));
        CHECK(c.keypoint[0] == Approx(5.0));
        CHECK(c.keypoint[1] == Approx(4.0));
        CHECK(c.keypoint[2] == Approx(3.0));
        CHECK(c.matched_keypoints == 10);
      }
    }
  }
}

SCENARIO("Similarity: self, symmetry and degenerate fingerprints") {
  Figure39 example;
  NgramSimilarity similarity;
  THEN("a fingerprint with itself scores 1") {
    CHECK(similarity.similarity(example.reference, example.reference) == Approx(1.0).margin(1e-9));
    CHECK(similarity.similarity(example.query, example.query) == Approx(1.0).margin(1e-9));
  }
  THEN("the Figure 3.9 pair scores the mean of the normalised counts") {
    const double hist = (2.45 / 5 + 1.65 / 4 + (2.45 / 3) / 3) / 3;
    const double kp = (2.1 / 5 + 1.55 / 4 + 0.7 / 3) / 3;
    CHECK(similarity.similarity(example.reference, example.query) == Approx(0.5 * hist + 0.5 * kp).epsilon(1e-6));
  }
  THEN("the two directions differ for this asymmetric pair and the symmetric value is their mean") {
    // Reversed roles: a keypoint letter scores matched / the new reference letter's keypoints, so
    // Q0-R1 gives 2/3 (not 2/4), Q1-R2 2/2, Q2-R3 stays 3/5 (both letters have 5). Histograms
    // are symmetric (Hellinger distance).
    const double hist = (2.45 / 5 + 1.65 / 4 + (2.45 / 3) / 3) / 3;
    const double kp_forward = (2.1 / 5 + 1.55 / 4 + 0.7 / 3) / 3;
    const double kp_1 = 2.0 / 3 + 1.0 + 0.6;
    const double kp_2 = (2.0 / 3 + 1.0) / 2 + (1.0 + 0.6) / 2;
    const double kp_backward = (kp_1 / 5 + kp_2 / 4 + (kp_1 / 3) / 3) / 3;
    const double forward = similarity.similarity(example.reference, example.query);
    const double backward = similarity.similarity(example.query, example.reference);
    CHECK(forward == Approx(0.5 * hist + 0.5 * kp_forward).epsilon(1e-6));
    CHECK(backward == Approx(0.5 * hist + 0.5 * kp_backward).epsilon(1e-6));
    CHECK(backward - forward > 0.01);
    CHECK(similarity.symmetricSimilarity(example.reference, example.query) ==
          Approx(0.5 * (forward + backward)).epsilon(1e-12));
  }
  GIVEN("fingerprints without keypoints or without subregions") {
    Fingerprint no_keypoints = example.reference;
    for (Subregion& s : no_keypoints.subregions) s.keypoint_begin = s.keypoint_end = 0;
    no_keypoints.keypoints.clear();
    no_keypoints.descriptors = cv::Mat();
    Fingerprint empty;
    THEN("keypoint-less frames compare by histograms only and an empty frame scores 0") {
      CHECK(similarity.similarity(no_keypoints, no_keypoints) == Approx(1.0));
      CHECK(similarity.similarity(example.reference, no_keypoints) == Approx(0.5));
      CHECK(similarity.similarity(empty, example.query) == 0.0);
      CHECK(similarity.similarity(example.query, empty) == 0.0);
    }
  }
}

SCENARIO("Hamming distance on any descriptor length matches OpenCV") {
  std::mt19937_64 rng(7);
  for (int bytes : {32, 61, 64, 5}) {
    const cv::Mat a = randomRows(20, bytes, rng);
    const cv::Mat b = randomRows(20, bytes, rng);
    for (int r = 0; r < 20; ++r) {
      CHECK(NgramMatcher::hammingDistance(a.ptr<std::uint8_t>(r), b.ptr<std::uint8_t>(r), bytes) ==
            static_cast<int>(cv::norm(a.row(r), b.row(r), cv::NORM_HAMMING)));
    }
    // Through the engine: a query equal to the reference matches every keypoint of every letter.
    const Fingerprint f = makeFingerprint({oneHot(0), oneHot(1)}, {a.rowRange(0, 10), a.rowRange(10, 20)});
    CHECK(NgramMatcher().counts(f, f).matched_keypoints == 20);
  }
}

SCENARIO("Hellinger distance") {
  CHECK(NgramMatcher::hellingerDistance(oneHot(3), oneHot(3)) == Approx(0.0).margin(1e-12));
  CHECK(NgramMatcher::hellingerDistance(oneHot(3), oneHot(4)) == Approx(1.0));
  HclHistogramBins half{};
  half[0] = half[1] = 0.5f;
  CHECK(NgramMatcher::hellingerDistance(oneHot(0), half) == Approx(std::sqrt(1.0 - std::sqrt(0.5))));
  CHECK(NgramMatcher::hellingerDistance(HclHistogramBins{}, HclHistogramBins{}) == 0.0);
  CHECK(NgramMatcher::hellingerDistance(HclHistogramBins{}, oneHot(0)) == 1.0);
  CHECK(NgramMatcher::hellingerDistance(atDistance(2, 0.2), oneHot(2)) == Approx(0.2).epsilon(1e-5));
}

SCENARIO("Localisation guards the degenerate cases") {
  Figure39 example;
  GIVEN("one place") {
    PlaceLocalizer localizer({}, {{"only", {example.reference}}});
    const Localization l = localizer.localize(example.query);
    THEN("it gets probability 1") {
      CHECK(l.best_place == 0);
      CHECK(l.best_probability == Approx(1.0));
    }
  }
  GIVEN("two places, one of them the query itself") {
    PlaceLocalizer localizer({}, {{"other", {example.reference}}, {"self", {example.reference, example.query}}});
    const Localization l = localizer.localize(example.query);
    THEN("the place holding the query wins with its best representative") {
      CHECK(l.best_place == 1);
      CHECK(l.places[1].best_reference == 1);
      CHECK(l.best_probability > 0.8);  // measured 0.887 (raw counts, alpha 0.01)
      CHECK(l.probabilities[0] + l.probabilities[1] == Approx(1.0));
    }
  }
  GIVEN("a query without subregions") {
    PlaceLocalizer localizer({}, {{"a", {example.reference}}, {"b", {example.query}}});
    const Localization l = localizer.localize(Fingerprint{});
    THEN("the result is uniform") { CHECK(l.probabilities[0] == Approx(0.5)); }
  }
  GIVEN("a query with subregions but no keypoints") {
    Fingerprint no_keypoints = example.reference;
    for (Subregion& s : no_keypoints.subregions) s.keypoint_begin = s.keypoint_end = 0;
    no_keypoints.keypoints.clear();
    no_keypoints.descriptors = cv::Mat();
    REQUIRE(no_keypoints.validate().empty());
    PlaceLocalizer localizer({}, {{"other", {example.query}}, {"self", {example.reference}}});
    const Localization l = localizer.localize(no_keypoints);
    THEN("the keypoint model is uniform and the histograms alone pick the right place") {
      for (const PlaceModel& m : l.keypoint.ngrams) {
        CHECK(m.probabilities[0] == Approx(0.5));
        CHECK(std::isfinite(m.weight));
      }
      CHECK(l.keypoint.probabilities[0] == Approx(0.5));
      CHECK(l.places[1].counts.query_keypoints == 0);
      CHECK(l.places[1].counts.keypoint[0] == 0.0);
      CHECK(l.best_place == 1);
      CHECK(l.probabilities[0] + l.probabilities[1] == Approx(1.0));
      CHECK(l.best_probability == Approx(l.histogram.probabilities[1]).epsilon(1e-9));
      CHECK(l.best_probability > 0.6);
    }
  }
  THEN("eq. 3.5-3.8 by hand, with a certain (zero-entropy) model not dividing by zero") {
    const InterpolatedModel m = PlaceLocalizer::interpolate({{{2.0, 0.0}, {1.0, 0.0}, {0.0, 0.0}}}, 0.01);
    CHECK(m.ngrams[0].probabilities[0] == Approx(2.01 / 2.02));
    CHECK(m.ngrams[2].probabilities[0] == Approx(0.5));
    CHECK(m.ngrams[2].entropy == Approx(std::log(2.0)));
    CHECK(m.ngrams[0].weight > m.ngrams[2].weight);
    const InterpolatedModel one = PlaceLocalizer::interpolate({{{0.0}, {0.0}, {0.0}}}, 0.01);
    CHECK(one.probabilities[0] == Approx(1.0));
    CHECK(std::isfinite(one.ngrams[0].weight));
  }
  THEN("bad construction is refused") {
    CHECK_THROWS_AS(PlaceLocalizer({}, {}), std::invalid_argument);
    CHECK_THROWS_AS(PlaceLocalizer({}, {{"empty", {}}}), std::invalid_argument);
    PlaceLocalizerConfig bad;
    bad.laplace_alpha = 0.0;
    CHECK_THROWS_WITH(PlaceLocalizer(bad, {{"a", {example.reference}}}), Catch::Contains("laplace_alpha"));
  }
}
