// Frame-level loop closures by sequence evidence: hand-computed steps of the detector, whole runs with
// tagged fingerprints (one lap, then the same lap again), keyframes at a camera rate, bad input.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "binary_fingerprints.hpp"
#include "fake_similarity.hpp"
#include "toposlam/topology/sequence_loop_closures.hpp"

using namespace toposlam;
using Catch::Matchers::Contains;
using Catch::Matchers::WithinAbs;

namespace {

/// Same tag 0.8, adjacent tags 0.3, otherwise 0.1 plus a fixed pseudo-random part in [0, 0.05).
test::TagSimilarity lapSimilarity() {
  return test::TagSimilarity([](int a, int b) {
    if (a == b) return 0.8;
    if (std::abs(a - b) == 1) return 0.3;
    const auto h = static_cast<std::uint32_t>(a * 7919 + b * 104729) * 2654435761u;
    return 0.1 + 0.05 * static_cast<double>(h >> 8) / static_cast<double>(1u << 24);
  });
}

}  // namespace

TEST_CASE("sequence loop detector: three steps computed by hand", "[sequence_loops]") {
  SequenceLoopConfig config;
  config.decay = 0.5;
  config.min_gap_keyframes = 1;
  SequenceLoopDetector detector(config);
  CHECK(detector.add({}).keyframe == -1);
  // One earlier keyframe: no spread to judge by, z = 0, no detection.
  CHECK(detector.add({0.3}).keyframe == -1);
  // The score is D in its noise's standard deviations: sqrt((1 - 0.5) / (1 + 0.5)) = 0.5774 at decay 0.5.
  const double noise = std::sqrt(0.5 / 1.5);
  // mean 0.4, std 0.2: z = (-1, 1); D = 0.5 z + 0.5 D(previous, g - 1) = (-0.5, 0.5).
  const SequenceLoopDetector::Detection third = detector.add({0.2, 0.6});
  CHECK(third.keyframe == 1);
  CHECK(third.diagonal == 1);
  CHECK_THAT(third.score, WithinAbs(0.5 / noise, 1e-12));
  CHECK_THAT(third.relative, WithinAbs(1.0, 1e-12));
  // mean 0.3, std sqrt(0.08): z = (-0.7071, -0.7071, 1.4142); D(3, 2) = 0.5 * 1.4142 + 0.5 * D(2, 1) = 0.9571.
  const SequenceLoopDetector::Detection fourth = detector.add({0.1, 0.1, 0.7});
  CHECK(fourth.keyframe == 2);
  CHECK_THAT(fourth.score, WithinAbs((0.5 * 0.2 / std::sqrt(0.08) * 2.0 + 0.25) / noise, 1e-9));
  CHECK(detector.keyframes() == 4);
}

TEST_CASE("sequence loop detector: no diagonal runs across the start of a traversal", "[sequence_loops]") {
  SequenceLoopConfig config;
  config.decay = 0.5;
  config.min_gap_keyframes = 1;
  // As in the hand-computed case (where D(3, 2) = 0.9571 carries D(2, 1) = 0.5), but keyframe 2 began a
  // traversal: D(3, 2) is its own evidence only.
  SequenceLoopDetector split(config);
  split.add({});
  split.add({0.3});
  split.add({0.2, 0.6}, false);
  const SequenceLoopDetector::Detection d = split.add({0.1, 0.1, 0.7});
  CHECK(d.keyframe == 2);
  CHECK_THAT(d.score, WithinAbs(0.5 * 0.4 / std::sqrt(0.08) / std::sqrt(0.5 / 1.5), 1e-9));
}

TEST_CASE("sequence loop detector: the minimum gap keeps recent keyframes out", "[sequence_loops]") {
  SequenceLoopConfig config;
  config.decay = 0.0;
  config.min_gap_keyframes = 2;
  SequenceLoopDetector detector(config);
  detector.add({});
  detector.add({0.5});
  // The newest earlier keyframe (g = 1, one back) stands out but is too recent; g = 0 is below the mean.
  CHECK(detector.add({0.1, 0.9}).keyframe == -1);
  // g = 0 is three back and stands out: detected.
  const auto d = detector.add({0.9, 0.1, 0.1});
  CHECK(d.keyframe == 0);
  CHECK(d.score > 1.0);
}

namespace {

/// The per-frame answers of PlaceSequenceEvidence over a whole stream (every detection counts: no score or
/// relative-similarity floor), as the segmentation stage gets them frame by frame.
std::vector<FrameRevisit> frameRevisits(const std::vector<double>& time_s,
                                        const std::vector<std::shared_ptr<const Fingerprint>>& fingerprints,
                                        const SimilarityMeasure& similarity, const SequenceLoopConfig& loop,
                                        double min_score = 0.0) {
  SequenceEvidenceConfig config;
  config.loop = loop;  // its decay and gap as memory_s and min_gap_s, the settings in seconds
  config.memory_s = loop.keyframe_interval_s / (1.0 - loop.decay);
  config.min_gap_s = loop.min_gap_keyframes * loop.keyframe_interval_s;
  config.min_score = min_score;
  PlaceSequenceEvidence detector(config, similarity);
  std::vector<FrameRevisit> out;
  for (std::size_t f = 0; f < fingerprints.size(); ++f) {
    if (f > 0 && time_s[f] < time_s[f - 1]) detector.beginTraversal();
    out.push_back(detector.addFrame(static_cast<std::int64_t>(f), time_s[f], fingerprints[f]));
  }
  return out;
}

}  // namespace

TEST_CASE("sequence loop closures: a second lap finds the first, the first lap finds nothing above it",
          "[sequence_loops]") {
  const int lap = 40;
  std::vector<double> time_s;
  std::vector<std::shared_ptr<const Fingerprint>> fingerprints;
  for (int traversal = 0; traversal < 2; ++traversal) {
    for (int i = 0; i < lap; ++i) {
      time_s.push_back(static_cast<double>(i));  // each traversal starts its clock at 0
      fingerprints.push_back(test::taggedFingerprint(i));
    }
  }
  const test::TagSimilarity similarity = lapSimilarity();
  SequenceLoopConfig config;
  config.min_gap_keyframes = 20;
  config.decay = 0.9;
  const std::vector<FrameRevisit> matches = frameRevisits(time_s, fingerprints, similarity, config);
  REQUIRE(matches.size() == 2u * lap);
  double first_lap_max = 0.0;
  for (int f = 0; f < lap; ++f) first_lap_max = std::max(first_lap_max, matches[static_cast<std::size_t>(f)].score);
  double second_lap_min = std::numeric_limits<double>::infinity();
  int right = 0;
  for (int f = lap; f < 2 * lap; ++f) {
    const FrameRevisit& m = matches[static_cast<std::size_t>(f)];
    if (m.match_frame == f - lap) ++right;
    if (f >= lap + 5) second_lap_min = std::min(second_lap_min, m.score);
  }
  CHECK(right == lap);  // every second-lap frame, from its first, on its first-lap twin
  // After five frames of the revisit its evidence is above anything the first lap ever scored, so recall
  // at 100 % precision is at least (lap - 5) / lap.
  CHECK(second_lap_min > first_lap_max);
  CHECK(first_lap_max < 0.5);
}

TEST_CASE("sequence loop closures: keyframes once a second, the frames between follow their keyframe's match",
          "[sequence_loops]") {
  // 5 frames per second, 150 frames a lap (30 s), every frame its own tag; the second lap retraces it.
  const int lap = 150;
  std::vector<double> time_s;
  std::vector<std::shared_ptr<const Fingerprint>> fingerprints;
  for (int traversal = 0; traversal < 2; ++traversal) {
    for (int i = 0; i < lap; ++i) {
      time_s.push_back(0.2 * i + 100.0 * traversal);
      fingerprints.push_back(test::taggedFingerprint(i));
    }
  }
  fingerprints[7] = nullptr;  // a frame without a fingerprint is never a keyframe
  const test::TagSimilarity similarity = lapSimilarity();
  const long before = similarity.calls();
  SequenceLoopConfig config;  // 1 s keyframes, 20 keyframes back, the default memories and published score
  config.scales = SequenceEvidenceConfig{}.loop.scales;
  const std::vector<FrameRevisit> matches =
      frameRevisits(time_s, fingerprints, similarity, config, SequenceEvidenceConfig{}.min_score);
  // 60 keyframes: 59 * 60 / 2 pairs (twice: symmetric) and nothing for the frames between.
  CHECK(similarity.calls() - before <= 2 * (59 * 60 / 2));
  int right = 0;
  for (int f = lap; f < 2 * lap; ++f) right += matches[static_cast<std::size_t>(f)].match_frame == f - lap ? 1 : 0;
  CHECK(right >= lap - 5);  // the frames of the revisit's first keyframe may still be unmatched
  for (int f = 0; f < 2 * lap; ++f) CHECK(matches[static_cast<std::size_t>(f)].match_frame < f);
  for (int f = 0; f < lap; ++f) CHECK(matches[static_cast<std::size_t>(f)].match_frame == -1);
}

TEST_CASE("sequence loop closures: bad settings and input are refused, naming what is wrong", "[sequence_loops]") {
  SequenceLoopConfig config;
  config.decay = 1.0;
  CHECK_THAT(config.validate(), Contains("decay"));
  config = {};
  config.min_gap_keyframes = 0;
  CHECK_THAT(config.validate(), Contains("gap"));
  config = {};
  config.keyframe_interval_s = std::numeric_limits<double>::quiet_NaN();
  CHECK_THAT(config.validate(), Contains("keyframe interval"));
  config = {};
  config.sigma_floor = 0.0;
  CHECK_THAT(config.validate(), Contains("sigma floor"));
  CHECK_THROWS_AS(SequenceLoopDetector(config), std::invalid_argument);

  SequenceLoopDetector detector{SequenceLoopConfig{}};
  detector.add({});
  CHECK_THROWS_WITH(detector.add({0.1, 0.2}), Contains("2 similarities for 1 earlier keyframes"));
  const test::TagSimilarity similarity = lapSimilarity();
  PlaceSequenceEvidence evidence(SequenceEvidenceConfig{}, similarity);
  evidence.addFrame(3, 0.0, test::taggedFingerprint(0));
  CHECK_THROWS_WITH(evidence.addFrame(3, 1.0, test::taggedFingerprint(1)), Contains("frame 3 after frame 3"));
}

TEST_CASE("place sequence evidence: a retraced lap points each place at its first-lap twin, the first lap at nothing",
          "[sequence_loops][evidence]") {
  // 1 Hz keyframes, two laps of 60 s cut into places of 15 s; the second lap retraces the first.
  const int lap = 60, place_length = 15;
  const test::TagSimilarity similarity = lapSimilarity();
  SequenceEvidenceConfig config;
  config.weight = 0.99;
  config.memory_s = 10.0;  // decay 0.9 at one keyframe a second
  PlaceSequenceEvidence evidence(config, similarity);
  std::vector<std::vector<double>> by_place;
  for (int traversal = 0; traversal < 2; ++traversal) {
    if (traversal == 1) evidence.beginTraversal();
    for (int i = 0; i < lap; ++i) {
      const std::int64_t frame = traversal * lap + i;
      evidence.addFrame(frame, static_cast<double>(i), test::taggedFingerprint(i));
      if ((i + 1) % place_length == 0) by_place.push_back(evidence.closePlace(frame - place_length + 1, frame));
    }
  }
  REQUIRE(by_place.size() == 8u);
  CHECK(evidence.keyframes() == 2 * lap);
  for (std::size_t p = 0; p < 8; ++p) {
    REQUIRE(by_place[p].size() == p);  // one value per earlier place
    if (p < 4) {
      for (const double e : by_place[p]) CHECK(e == 0.0);  // the first lap has no twin
      continue;
    }
    // Place p of the second lap: every keyframe after the first few detects into place p - 4.
    for (std::size_t q = 0; q < p; ++q) {
      if (q == p - 4) {
        CHECK(by_place[p][q] >= 0.99 * 0.8);
        CHECK(by_place[p][q] <= 0.99);
      } else {
        CHECK(by_place[p][q] == 0.0);
      }
    }
  }
}

TEST_CASE("place sequence evidence: a share below min_share gives nothing, a dropped place's keyframes do not count",
          "[sequence_loops][evidence]") {
  const test::TagSimilarity similarity = lapSimilarity();
  // Frames 0..29 (tags 0..29); 30..39 retrace 0..9 and 40..49 are new (tags 140..149), closed as one place
  // with about half its keyframes on place 0; 50..59 retrace 10..19 in a dropped place (never closed);
  // 60..69 retrace 20..29, all of them on place 0.
  const auto run = [&](double min_share) {
    SequenceEvidenceConfig config;
    config.weight = 0.5;
    config.memory_s = 10.0;
    config.min_gap_s = 10.0;
    // One memory, and the keyframe's own similarity must stand out too: the new keyframes 40..49 then stop
    // voting for place 0 at once (with the long memory alone the retraced run's evidence carries on).
    config.loop.scales = 1;
    config.min_score = 0.1 / std::sqrt(0.1 / 1.9);
    config.min_relative = 0.0;
    config.min_share = min_share;
    PlaceSequenceEvidence evidence(config, similarity);
    for (int i = 0; i < 30; ++i) evidence.addFrame(i, i, test::taggedFingerprint(i));
    std::vector<std::vector<double>> out{evidence.closePlace(0, 29)};
    for (int i = 30; i < 40; ++i) evidence.addFrame(i, i, test::taggedFingerprint(i - 30));
    for (int i = 40; i < 50; ++i) evidence.addFrame(i, i, test::taggedFingerprint(100 + i));
    out.push_back(evidence.closePlace(30, 49));
    for (int i = 50; i < 70; ++i) evidence.addFrame(i, i, test::taggedFingerprint(i - 40));
    out.push_back(evidence.closePlace(60, 69));
    return out;
  };
  const std::vector<std::vector<double>> strict = run(0.8), loose = run(0.0);
  CHECK(strict[0].empty());
  REQUIRE(strict[1].size() == 1u);
  REQUIRE(loose[1].size() == 1u);
  CHECK(loose[1][0] >= 0.5 * 0.5);  // at least the ten retraced keyframes of twenty
  CHECK(loose[1][0] < 0.5 * 0.8);
  CHECK(strict[1][0] == 0.0);       // ... below the share that counts
  REQUIRE(strict[2].size() == 2u);
  CHECK_THAT(strict[2][0], WithinAbs(0.5, 1e-12));  // ten of ten keyframes, the dropped place's not counted
  CHECK(strict[2][1] == 0.0);
}

TEST_CASE("place sequence evidence: bad settings and input are refused", "[sequence_loops][evidence]") {
  SequenceEvidenceConfig config;
  config.weight = 1.5;
  CHECK_THAT(config.validate(), Contains("weight"));
  config = {};
  config.min_share = -0.1;
  CHECK_THAT(config.validate(), Contains("share"));
  config = {};
  config.min_score = std::numeric_limits<double>::quiet_NaN();
  CHECK_THAT(config.validate(), Contains("score"));
  config = {};
  config.memory_s = 0.5;
  CHECK_THAT(config.validate(), Contains("memory"));
  config = {};
  config.min_gap_s = 0.0;
  CHECK_THAT(config.validate(), Contains("gap"));
  config = {};
  config.loop.scales = 9;
  CHECK_THAT(config.validate(), Contains("scales"));
  const test::TagSimilarity similarity = lapSimilarity();
  CHECK_THROWS_AS(PlaceSequenceEvidence(config, similarity), std::invalid_argument);
  PlaceSequenceEvidence evidence(SequenceEvidenceConfig{}, similarity);
  evidence.addFrame(5, 0.0, test::taggedFingerprint(0));
  CHECK_THROWS_WITH(evidence.addFrame(5, 1.0, test::taggedFingerprint(1)), Contains("after frame 5"));
  CHECK_THROWS_AS(evidence.closePlace(3, 2), std::invalid_argument);
  evidence.closePlace(0, 5);
  CHECK_THROWS_WITH(evidence.closePlace(5, 9), Contains("overlaps"));
}

TEST_CASE("sequence loop closures: beyond exhaustive_up_to a keyframe costs a bounded number of comparisons and the "
          "second lap is still found", "[sequence_loops][large]") {
  // Two laps of 150 keyframes (1 Hz), each tag's keyframe with its own binary descriptors (seen again with 20
  // of 256 bits changed), so the candidate index finds the twin; the lap similarity scores the pairs.
  const int lap = 150;
  const test::TagSimilarity similarity = lapSimilarity();
  const auto run = [&](int exhaustive_up_to) {
    SequenceEvidenceConfig config;
    config.exhaustive_up_to = exhaustive_up_to;
    config.candidates = 8;
    config.diagonals = 8;
    config.statistics_sample = 32;
    PlaceSequenceEvidence detector(config, similarity);
    std::vector<FrameRevisit> answers;
    std::vector<std::int64_t> cost;  // comparisons of each keyframe
    for (int k = 0; k < 2 * lap; ++k) {
      const int tag = k % lap;
      const std::int64_t before = detector.comparisons();
      answers.push_back(detector.addFrame(k, static_cast<double>(k),
                                          test::fingerprintWith(tag, test::withNoise(test::placeDescriptors(tag, 40), 20,
                                                                                     static_cast<std::uint64_t>(k)))));
      cost.push_back(detector.comparisons() - before);
    }
    return std::make_pair(answers, cost);
  };
  const auto [exact, exact_cost] = run(1000000);
  const auto [sparse, sparse_cost] = run(30);
  int exact_right = 0, sparse_right = 0, sparse_wrong = 0;
  for (int k = lap; k < 2 * lap; ++k) {
    exact_right += exact[static_cast<std::size_t>(k)].match_frame == k - lap ? 1 : 0;
    const std::int64_t m = sparse[static_cast<std::size_t>(k)].match_frame;
    sparse_right += m == k - lap ? 1 : 0;
    sparse_wrong += m >= 0 && m != k - lap ? 1 : 0;
  }
  CHECK(exact_right >= lap - 10);
  CHECK(sparse_right >= exact_right - 5);
  CHECK(sparse_wrong <= 2);
  // Exhaustive: one comparison per earlier keyframe. Beyond 30 keyframes: at most the sample, the candidates
  // and their neighbours, and three keyframes for each of the 8 diagonals of each of the 3 memories.
  CHECK(exact_cost.back() == 2 * lap - 1);
  for (int k = 31; k < 2 * lap; ++k) CHECK(sparse_cost[static_cast<std::size_t>(k)] <= 32 + 3 * 8 + 3 * 3 * 8);
  CHECK(sparse_cost[30] == 30);  // up to exhaustive_up_to keyframes, every earlier one
}

namespace {

/// The per-frame answers of a stream of tags at 1 Hz (one keyframe a second, one clock) with the default
/// published score and the given margin over the runner-up.
std::vector<FrameRevisit> publishedRevisits(const std::vector<int>& tags, const SimilarityMeasure& similarity,
                                            double min_margin) {
  SequenceEvidenceConfig config;  // memory 40 s, 3 memories, 20 s gap, score >= 2, runs within 5 s are one
  config.min_margin = min_margin;
  PlaceSequenceEvidence evidence(config, similarity);
  std::vector<FrameRevisit> out;
  for (std::size_t f = 0; f < tags.size(); ++f)
    out.push_back(evidence.addFrame(static_cast<std::int64_t>(f), static_cast<double>(f), test::taggedFingerprint(tags[f])));
  return out;
}

/// Same tag 0.8, otherwise a fixed pseudo-random similarity in [0.1, 0.15); tags are compared modulo
/// `period` (0: not at all), so a building whose stretches repeat every `period` tags looks periodic.
test::TagSimilarity periodicSimilarity(int period) {
  return test::TagSimilarity([period](int a, int b) {
    if (a == b || (period > 0 && a % period == b % period)) return 0.8;
    const auto h = static_cast<std::uint32_t>(a * 7919 + b * 104729) * 2654435761u;
    return 0.1 + 0.05 * static_cast<double>(h >> 8) / static_cast<double>(1u << 24);
  });
}

}  // namespace

TEST_CASE("sequence loop closures: a run that does not stand out from another run is not published (min_margin)",
          "[sequence_loops]") {
  // A stretch of ten views seen twice in a row (the same ten doors on both halves of a corridor: too recent
  // to match each other, 10 s < the 20 s gap), 40 s elsewhere, then the stretch again: it matches both of
  // its earlier halves in step, equally. Where the robot is cannot be told, so nothing is published with a
  // margin, and the detector alone publishes it.
  std::vector<int> tags;
  for (int half = 0; half < 2; ++half)
    for (int i = 0; i < 10; ++i) tags.push_back(i);
  for (int i = 0; i < 40; ++i) tags.push_back(100 + i);
  for (int i = 0; i < 10; ++i) tags.push_back(i);
  for (int i = 0; i < 20; ++i) tags.push_back(200 + i);
  const test::TagSimilarity similarity = periodicSimilarity(0);
  // Counted over the stretch's return (frames 60-69; what follows it is docs/topology.md's "after leaving").
  const auto published = [&](const std::vector<FrameRevisit>& revisits, std::size_t from) {
    int count = 0;
    for (std::size_t f = from; f < from + 10; ++f) count += revisits[f].match_frame >= 0;
    return count;
  };
  CHECK(published(publishedRevisits(tags, similarity, 0.0), 60) >= 8);  // from its second or third view on
  CHECK(published(publishedRevisits(tags, similarity, 0.5), 60) == 0);
  // The same route with the stretch seen once: it stands out and is published with the margin too.
  const std::vector<int> once(tags.begin() + 10, tags.end());
  const std::vector<FrameRevisit> revisits = publishedRevisits(once, similarity, 0.5);
  CHECK(published(revisits, 50) >= 8);
  for (std::size_t f = 50; f < 60; ++f)
    if (revisits[f].match_frame >= 0) CHECK(once[static_cast<std::size_t>(revisits[f].match_frame)] == once[f]);
}

TEST_CASE("sequence loop closures: a third visit is published although it matches both earlier ones",
          "[sequence_loops]") {
  // A 60 s route driven three times in one stream (no clock reset): the third visit matches the first and
  // the second alike. The second visit's published matches made them one place, so the third stands out.
  std::vector<int> tags;
  for (int visit = 0; visit < 3; ++visit)
    for (int i = 0; i < 60; ++i) tags.push_back(i);
  const test::TagSimilarity similarity = periodicSimilarity(0);
  const std::vector<FrameRevisit> revisits = publishedRevisits(tags, similarity, 1.0);
  int first = 0, second = 0, third = 0, wrong = 0;
  for (std::size_t f = 0; f < tags.size(); ++f) {
    const FrameRevisit& r = revisits[f];
    if (r.match_frame < 0) continue;
    if (tags[static_cast<std::size_t>(r.match_frame)] != tags[f]) {
      ++wrong;
      continue;
    }
    (f < 60 ? first : f < 120 ? second : third) += 1;
  }
  CHECK(first == 0);
  CHECK(wrong == 0);
  CHECK(second >= 55);
  CHECK(third >= 55);
}
