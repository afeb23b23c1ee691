// FiedlerSegmenter and fiedlerValue: the thesis' worked numbers (Figure 4.2, eq. 4.6), degenerate
// windows, the similarity cache, and synthetic streams of blocks of near-identical frames.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

#include "fake_similarity.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"

using toposlam::CutPlacement;
using toposlam::parseRepresentativeChoice;
using toposlam::RepresentativeChoice;
using toposlam::toString;
using toposlam::FiedlerSegmenter;
using toposlam::FiedlerSegmenterConfig;
using toposlam::SegmentedPlace;
using toposlam::test::fakeFingerprint;
using toposlam::test::TableSimilarity;
using toposlam::test::thesisConfig;

namespace {

Eigen::MatrixXd figure42Graph() {
  // Nodes 1..6 of Figure 4.2 as rows/columns 0..5 (thesis eq. 4.2).
  Eigen::MatrixXd a(6, 6);
  a << 0, 1, 0, 0, 0, 0,  //
      1, 0, 1, 1, 0, 0,   //
      0, 1, 0, 1, 1, 0,   //
      0, 1, 1, 0, 0, 1,   //
      0, 0, 1, 0, 0, 1,   //
      0, 0, 0, 1, 1, 0;
  return a;
}

// Block id of each frame for blocks of the given lengths.
std::vector<int> blockLabels(const std::vector<int>& lengths) {
  std::vector<int> labels;
  for (std::size_t b = 0; b < lengths.size(); ++b)
    labels.insert(labels.end(), static_cast<std::size_t>(lengths[b]), static_cast<int>(b));
  return labels;
}

// Near-identical frames inside a block (0.85 .. 0.95, a deterministic wobble so no two windows tie
// exactly), nearly unrelated across blocks (0.05).
double blockSimilarity(const std::vector<int>& labels, int a, int b) {
  if (labels[static_cast<std::size_t>(a)] != labels[static_cast<std::size_t>(b)]) return 0.05;
  return 0.9 + 0.05 * std::sin(0.7 * a + 1.3 * b);
}

struct Run {
  std::vector<SegmentedPlace> places;  // in closing order, flush included
  std::vector<std::optional<double>> lambda2;
};

Run runStream(FiedlerSegmenter& segmenter, int frames, const std::function<int(int)>& keypoints = {}) {
  Run run;
  for (int f = 0; f < frames; ++f) {
    auto step = segmenter.addFrame(f, 0.2 * f, fakeFingerprint(f, keypoints ? keypoints(f) : 50));
    run.lambda2.push_back(step.lambda2);
    if (step.closed_place) run.places.push_back(*step.closed_place);
  }
  if (auto last = segmenter.flush()) run.places.push_back(*last);
  return run;
}

}  // namespace

TEST_CASE(
    "GIVEN the graph of Figure 4.2 WHEN its Fiedler value is computed THEN it is 0.454, and 0.512 with "
    "the extra edge 1-3",
    "[segmentation][fiedler]") {
  Eigen::MatrixXd a = figure42Graph();
  CHECK(toposlam::fiedlerValue(a) == Approx(0.454).margin(0.0005));
  a(0, 2) = a(2, 0) = 1.0;
  CHECK(toposlam::fiedlerValue(a) == Approx(0.512).margin(0.0005));
}

TEST_CASE("GIVEN a fully connected window WHEN lambda2 is computed THEN it is n/(n-1) (eq. 4.6)",
          "[segmentation][fiedler]") {
  for (int n : {2, 3, 10, 25}) {
    Eigen::MatrixXd a = Eigen::MatrixXd::Ones(n, n);
    CHECK(toposlam::fiedlerValue(a) == Approx(static_cast<double>(n) / (n - 1)).epsilon(1e-12));
    CHECK(toposlam::maxFiedlerValue(n) == Approx(static_cast<double>(n) / (n - 1)));
  }
  CHECK(toposlam::maxFiedlerValue(25) == Approx(1.0417).margin(0.0001));
  SECTION("weights scale out: a complete graph with all similarities 0.3 gives the same 25/24") {
    CHECK(toposlam::fiedlerValue(Eigen::MatrixXd::Constant(25, 25, 0.3)) ==
          Approx(25.0 / 24.0).epsilon(1e-12));
  }
}

TEST_CASE("GIVEN degenerate affinities WHEN lambda2 is computed THEN it is defined and finite",
          "[segmentation][fiedler]") {
  SECTION("all-zero similarities: every node isolated, lambda2 = 0") {
    CHECK(toposlam::fiedlerValue(Eigen::MatrixXd::Zero(25, 25)) == 0.0);
  }
  SECTION("one isolated node among a connected group: disconnected, lambda2 = 0") {
    Eigen::MatrixXd a = Eigen::MatrixXd::Ones(5, 5);
    a.row(4).setZero();
    a.col(4).setZero();
    CHECK(toposlam::fiedlerValue(a) == Approx(0.0).margin(1e-12));
  }
  SECTION("two disconnected cliques: lambda2 = 0") {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(6, 6);
    a.topLeftCorner(3, 3).setOnes();
    a.bottomRightCorner(3, 3).setOnes();
    CHECK(toposlam::fiedlerValue(a) == Approx(0.0).margin(1e-12));
  }
  SECTION("fewer than two nodes: 0; a non-square matrix is refused") {
    CHECK(toposlam::fiedlerValue(Eigen::MatrixXd::Ones(1, 1)) == 0.0);
    CHECK_THROWS_WITH(toposlam::fiedlerValue(Eigen::MatrixXd::Ones(2, 3)), Catch::Contains("square"));
  }
  SECTION("negative or NaN similarities count as no link") {
    Eigen::MatrixXd a = Eigen::MatrixXd::Ones(4, 4);
    a(0, 1) = a(1, 0) = -3.0;
    a(2, 3) = a(3, 2) = NAN;
    const double value = toposlam::fiedlerValue(a);
    CHECK(std::isfinite(value));
    Eigen::MatrixXd b = Eigen::MatrixXd::Ones(4, 4);
    b(0, 1) = b(1, 0) = 0.0;
    b(2, 3) = b(3, 2) = 0.0;
    CHECK(value == Approx(toposlam::fiedlerValue(b)));
  }
}

TEST_CASE(
    "GIVEN identical frames streaming in WHEN each is added THEN lambda2 follows k/(k-1) and reaches 25/24",
    "[segmentation][segmenter]") {
  TableSimilarity similarity([](int, int) { return 0.9; });
  FiedlerSegmenter segmenter(thesisConfig(), similarity);
  const Run run = runStream(segmenter, 40);
  CHECK_FALSE(run.lambda2[0].has_value());
  REQUIRE(run.lambda2[1].has_value());
  CHECK(*run.lambda2[1] == Approx(2.0));
  CHECK(*run.lambda2[2] == Approx(1.5));
  CHECK(*run.lambda2[24] == Approx(25.0 / 24.0));
  CHECK(*run.lambda2[39] == Approx(25.0 / 24.0));
  THEN("there is no valley, and flush closes the single place [0, 39]") {
    REQUIRE(run.places.size() == 1);
    CHECK(run.places[0].first_frame == 0);
    CHECK(run.places[0].last_frame == 39);
    CHECK(run.places[0].valley_frame == -1);
    CHECK_FALSE(run.places[0].dropped);
    CHECK(run.places[0].representative != nullptr);
  }
}

TEST_CASE(
    "GIVEN a window of n frames WHEN a new frame arrives THEN only its 2(n-1) similarities are computed",
    "[segmentation][segmenter]") {
  TableSimilarity similarity([](int a, int b) { return a == b ? 1.0 : 0.5; });
  FiedlerSegmenterConfig config = thesisConfig();
  config.window = 25;
  FiedlerSegmenter segmenter(config, similarity);
  for (int f = 0; f < 60; ++f) {
    similarity.resetCalls();
    segmenter.addFrame(f, 0.0, fakeFingerprint(f));
    const long expected = 2L * std::min(f, config.window - 1);
    REQUIRE(similarity.calls() == expected);
  }
  CHECK(segmenter.windowFrames() == 25);
  THEN("the cached affinity in window order equals the table for the last 25 frames") {
    const Eigen::MatrixXd a = segmenter.affinityInWindowOrder();
    REQUIRE(a.rows() == 25);
    CHECK(a.diagonal().isZero());
    CHECK(a(0, 1) == 0.5);
    CHECK((a - a.transpose()).isZero());
  }
}

TEST_CASE(
    "GIVEN an asymmetric similarity WHEN frames are added THEN the affinity is the mean of both directions",
    "[segmentation][segmenter]") {
  TableSimilarity similarity([](int reference, int query) { return reference < query ? 0.2 : 0.6; });
  FiedlerSegmenter segmenter(thesisConfig(), similarity);
  for (int f = 0; f < 3; ++f) segmenter.addFrame(f, 0.0, fakeFingerprint(f));
  const Eigen::MatrixXd a = segmenter.affinityInWindowOrder();
  CHECK(a(0, 1) == Approx(0.4));
  CHECK(a(2, 1) == Approx(0.4));
}

TEST_CASE(
    "GIVEN a stream of blocks of near-identical frames WHEN segmented THEN places are cut at the block "
    "borders",
    "[segmentation][segmenter]") {
  const std::vector<int> lengths = {40, 35, 45, 30};
  const std::vector<int> labels = blockLabels(lengths);
  TableSimilarity similarity([&](int a, int b) { return blockSimilarity(labels, a, b); });

  SECTION("window-split (default): exactly at the borders 40, 75 and 120") {
    FiedlerSegmenter segmenter(thesisConfig(), similarity);
    const Run run = runStream(segmenter, static_cast<int>(labels.size()));
    REQUIRE(run.places.size() == 4);
    const std::vector<std::pair<std::int64_t, std::int64_t>> expected = {
        {0, 39}, {40, 74}, {75, 119}, {120, 149}};
    for (std::size_t i = 0; i < 4; ++i) {
      CHECK(run.places[i].first_frame == expected[i].first);
      CHECK(run.places[i].last_frame == expected[i].second);
      CHECK(run.places[i].index == static_cast<std::int64_t>(i));
      CHECK_FALSE(run.places[i].dropped);
    }
    THEN("the valley of lambda2 is about half a window after each border, and lambda2 there is low") {
      for (std::size_t i = 0; i < 3; ++i) {
        const std::int64_t border = expected[i + 1].first;
        INFO("border " << border << " valley " << run.places[i].valley_frame);
        CHECK(run.places[i].valley_frame >= border + 10);
        CHECK(run.places[i].valley_frame <= border + 13);
        CHECK(*run.lambda2[static_cast<std::size_t>(run.places[i].valley_frame)] < 0.2);
      }
      CHECK(run.places[3].valley_frame == -1);  // closed by flush
      CHECK(segmenter.ignoredValleys() == 0);
    }
    THEN("times are passed through") {
      CHECK(run.places[1].first_time_s == Approx(0.2 * 40));
      CHECK(run.places[1].last_time_s == Approx(0.2 * 74));
    }
  }
  SECTION("valley-frame (Algorithm 4.1 read literally): each place ends at the valley frame") {
    FiedlerSegmenterConfig config = thesisConfig();
    config.cut_placement = CutPlacement::ValleyFrame;
    FiedlerSegmenter segmenter(config, similarity);
    const Run run = runStream(segmenter, static_cast<int>(labels.size()));
    REQUIRE(run.places.size() == 4);
    std::int64_t expected_first = 0;
    for (std::size_t i = 0; i < 3; ++i) {
      CHECK(run.places[i].first_frame == expected_first);
      CHECK(run.places[i].last_frame == run.places[i].valley_frame);
      expected_first = run.places[i].last_frame + 1;
    }
    // With a 25-frame window the most even split (12 | 13) is the valley: border + 11 or + 12.
    CHECK(run.places[0].last_frame >= 40 + 11);
    CHECK(run.places[0].last_frame <= 40 + 12);
    CHECK(run.places[3].last_frame == 149);
  }
}

TEST_CASE(
    "GIVEN blocks where one frame is most similar to the rest WHEN segmented THEN it is the representative",
    "[segmentation][segmenter]") {
  const std::vector<int> labels = blockLabels({50, 50, 50});
  const std::vector<int> best = {17, 71, 128};  // the most similar frame of each block
  auto quality = [&](int f) {
    for (int b : best)
      if (f == b) return 0.08;
    return 0.0;
  };
  TableSimilarity similarity([&](int a, int b) {
    if (labels[static_cast<std::size_t>(a)] != labels[static_cast<std::size_t>(b)]) return 0.05;
    return 0.8 + quality(a) + quality(b) + 0.01 * std::sin(0.7 * a + 1.3 * b);
  });
  FiedlerSegmenter segmenter(thesisConfig(), similarity);
  const Run run = runStream(segmenter, 150);
  REQUIRE(run.places.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(run.places[i].first_frame == static_cast<std::int64_t>(50 * i));
    CHECK(run.places[i].representative_frame == best[i]);
    REQUIRE(run.places[i].representative != nullptr);
    CHECK(run.places[i].representative->image_width == best[i]);
    // Its degree: 24 links of about 0.8 + 0.08 inside a full window of its block.
    CHECK(run.places[i].representative_degree == Approx(24 * 0.88).margin(0.3));
  }
}

TEST_CASE("GIVEN a block whose frames have few keypoints WHEN segmented THEN its place is dropped",
          "[segmentation][segmenter]") {
  const std::vector<int> labels = blockLabels({40, 40, 40});
  TableSimilarity similarity([&](int a, int b) { return blockSimilarity(labels, a, b); });
  FiedlerSegmenterConfig config = thesisConfig();
  config.min_keypoints = 15;
  FiedlerSegmenter segmenter(config, similarity);
  const Run run =
      runStream(segmenter, 120, [&](int f) { return labels[static_cast<std::size_t>(f)] == 1 ? 14 : 15; });
  REQUIRE(run.places.size() == 3);
  CHECK_FALSE(run.places[0].dropped);
  CHECK(run.places[1].dropped);
  CHECK(run.places[1].representative_keypoints == 14);
  CHECK_FALSE(run.places[2].dropped);
  THEN("kept and dropped places are numbered separately") {
    CHECK(run.places[0].index == 0);
    CHECK(run.places[1].index == 0);
    CHECK(run.places[2].index == 1);
  }
}

TEST_CASE(
    "GIVEN a block whose most similar frame has too few keypoints WHEN segmented THEN a keypoint-rich member "
    "represents it and the place is kept",
    "[segmentation][segmenter]") {
  // Block 1's most similar frame (71, a bare doorway view) has 3 keypoints; frame 64 is the most similar
  // of the keypoint-rich ones. The thesis' rule would pick 71 and drop the place.
  const std::vector<int> labels = blockLabels({50, 50, 50});
  auto quality = [](int f) { return f == 71 ? 0.1 : f == 64 ? 0.05 : 0.0; };
  TableSimilarity similarity([&](int a, int b) {
    if (labels[static_cast<std::size_t>(a)] != labels[static_cast<std::size_t>(b)]) return 0.05;
    return 0.8 + quality(a) + quality(b) + 0.01 * std::sin(0.7 * a + 1.3 * b);
  });
  FiedlerSegmenter segmenter(thesisConfig(), similarity);
  const Run run = runStream(segmenter, 150, [](int f) { return f == 71 ? 3 : 40; });
  REQUIRE(run.places.size() == 3);
  CHECK_FALSE(run.places[1].dropped);
  CHECK(run.places[1].representative_frame == 64);
  CHECK(run.places[1].representative_keypoints == 40);
  WHEN("no member has enough keypoints") {
    FiedlerSegmenter poor(thesisConfig(), similarity);
    const Run dropped = runStream(poor, 150, [&](int f) { return labels[static_cast<std::size_t>(f)] == 1 ? 3 : 40; });
    REQUIRE(dropped.places.size() == 3);
    THEN("the most similar frame represents it and the place is dropped") {
      CHECK(dropped.places[1].dropped);
      CHECK(dropped.places[1].representative_frame == 71);
    }
  }
}

TEST_CASE(
    "GIVEN blocks that still match about 0.3 across borders WHEN a similarity floor of 0.3 is subtracted THEN "
    "the valleys of lambda2 deepen towards 0 and the cuts stay at the borders",
    "[segmentation][segmenter]") {
  const std::vector<int> labels = blockLabels({40, 35, 45});
  TableSimilarity similarity([&](int a, int b) {
    if (labels[static_cast<std::size_t>(a)] != labels[static_cast<std::size_t>(b)])
      return 0.32 + 0.02 * std::sin(1.1 * a + 0.4 * b);
    return 0.9 + 0.05 * std::sin(0.7 * a + 1.3 * b);
  });
  FiedlerSegmenterConfig plain;
  plain.window = 30;  // a window of 30 frames (window_s 0)
  FiedlerSegmenterConfig floored = plain;
  floored.similarity_floor = 0.3;
  FiedlerSegmenter without_floor(plain, similarity);
  FiedlerSegmenter with_floor(floored, similarity);
  const Run a = runStream(without_floor, 120);
  const Run b = runStream(with_floor, 120);
  double min_a = 10.0, min_b = 10.0;
  for (std::size_t f = 24; f < 120; ++f) {
    min_a = std::min(min_a, *a.lambda2[f]);
    min_b = std::min(min_b, *b.lambda2[f]);
  }
  INFO("lowest lambda2 without the floor " << min_a << ", with it " << min_b);
  CHECK(min_a > 0.3);   // ~0.32 across and ~0.9 inside: the split window stays well connected
  CHECK(min_b < 0.1);   // floored: 0 .. 0.04 across, a split window is nearly disconnected
  REQUIRE(b.places.size() == 3);
  CHECK(b.places[1].first_frame == 40);
  CHECK(b.places[2].first_frame == 75);
  THEN("a floor outside [0, 1) is refused by name") {
    FiedlerSegmenterConfig bad;
    bad.similarity_floor = 1.0;
    CHECK_THAT(bad.validate(), Catch::StartsWith("similarity_floor:"));
    bad.similarity_floor = -0.1;
    CHECK_THAT(bad.validate(), Catch::StartsWith("similarity_floor:"));
  }
}

TEST_CASE(
    "GIVEN all-zero similarities WHEN segmented THEN lambda2 is 0, nothing is cut, flush closes one place",
    "[segmentation][segmenter]") {
  TableSimilarity similarity([](int, int) { return 0.0; });
  FiedlerSegmenter segmenter(thesisConfig(), similarity);
  const Run run = runStream(segmenter, 30);
  for (std::size_t f = 1; f < 30; ++f) CHECK(*run.lambda2[f] == 0.0);
  REQUIRE(run.places.size() == 1);
  CHECK(run.places[0].first_frame == 0);
  CHECK(run.places[0].last_frame == 29);
  CHECK(run.places[0].representative_frame == 0);  // all degrees 0: the earliest frame
}

TEST_CASE("GIVEN flush WHEN called on an empty segmenter or twice THEN it closes at most one place",
          "[segmentation][segmenter]") {
  TableSimilarity similarity([](int, int) { return 0.7; });
  FiedlerSegmenter segmenter(thesisConfig(), similarity);
  CHECK_FALSE(segmenter.flush().has_value());
  segmenter.addFrame(0, 0.0, fakeFingerprint(0));
  auto only = segmenter.flush();
  REQUIRE(only.has_value());
  CHECK(only->first_frame == 0);
  CHECK(only->last_frame == 0);
  CHECK(only->representative_frame == 0);
  CHECK_FALSE(segmenter.flush().has_value());
  THEN("frames after a flush open a new place") {
    segmenter.addFrame(5, 1.0, fakeFingerprint(5));
    segmenter.addFrame(7, 1.4, fakeFingerprint(7));
    auto next = segmenter.flush();
    REQUIRE(next.has_value());
    CHECK(next->first_frame == 5);
    CHECK(next->last_frame == 7);
    CHECK(next->first_time_s == 1.0);
    CHECK(next->last_time_s == Approx(1.4));
  }
}

TEST_CASE("GIVEN bad input WHEN added THEN it is refused with a clear message", "[segmentation][segmenter]") {
  TableSimilarity similarity([](int, int) { return 0.7; });
  SECTION("invalid configs name the key") {
    FiedlerSegmenterConfig config = thesisConfig();
    config.window = 2;
    CHECK_THROWS_WITH(FiedlerSegmenter(config, similarity), Catch::Contains("window"));
    config = {};
    config.valley.gamma = 1.5;  // above 25/24
    CHECK_THROWS_WITH(FiedlerSegmenter(config, similarity), Catch::Contains("gamma"));
    config = {};
    config.min_keypoints = -1;
    CHECK_THROWS_WITH(FiedlerSegmenter(config, similarity), Catch::Contains("min_keypoints"));
  }
  SECTION("frame indices must increase; fingerprints must not be null") {
    FiedlerSegmenter segmenter(thesisConfig(), similarity);
    segmenter.addFrame(3, 0.0, fakeFingerprint(3));
    CHECK_THROWS_WITH(segmenter.addFrame(3, 0.0, fakeFingerprint(3)), Catch::Contains("increase"));
    CHECK_THROWS_WITH(segmenter.addFrame(4, 0.0, nullptr), Catch::Contains("null"));
  }
  SECTION("cut placement names parse both ways") {
    CHECK(toposlam::parseCutPlacement("valley-frame") == CutPlacement::ValleyFrame);
    CHECK(std::string(toposlam::toString(CutPlacement::WindowSplit)) == "window-split");
    CHECK_THROWS_WITH(toposlam::parseCutPlacement("middle"), Catch::Contains("window-split"));
  }
}

TEST_CASE(
    "GIVEN the same places filmed at 5, 10 and 15 fps WHEN the window is in seconds THEN the borders fall at "
    "the same times",
    "[segmentation][time]") {
  // Four places of 8, 12, 6 and 10 seconds. At f fps frame k is taken at k / f s and shows the place of
  // that time; similarities as in the block streams above.
  const std::vector<double> ends = {8.0, 20.0, 26.0, 36.0};
  const auto placeAt = [&](double t) {
    int p = 0;
    while (p + 1 < static_cast<int>(ends.size()) && t >= ends[static_cast<std::size_t>(p)]) ++p;
    return p;
  };
  std::vector<std::vector<double>> border_times;
  for (const double fps : {5.0, 10.0, 15.0}) {
    const int frames = static_cast<int>(ends.back() * fps);
    std::vector<int> labels;
    for (int k = 0; k < frames; ++k) labels.push_back(placeAt(k / fps));
    TableSimilarity similarity([&](int a, int b) { return blockSimilarity(labels, a, b); });
    FiedlerSegmenterConfig config;
    config.window_s = 5.0;   // the thesis' 25 frames at 5 fps
    config.window = 200;     // room for 15 fps
    config.min_window_frames = 5;
    FiedlerSegmenter segmenter(config, similarity);
    std::vector<double> borders;
    for (int k = 0; k < frames; ++k) {
      const auto step = segmenter.addFrame(k, k / fps, fakeFingerprint(k));
      if (k > 0) CHECK(segmenter.windowFrames() <= static_cast<int>(std::lround(5.0 * fps)) + 1);
      if (step.closed_place) borders.push_back(step.closed_place->last_time_s);
    }
    INFO(fps << " fps: " << borders.size() << " borders");
    REQUIRE(borders.size() == 3);
    border_times.push_back(borders);
  }
  // The same borders in time, within a frame of the slowest rate (0.2 s) plus rounding of the split.
  for (std::size_t b = 0; b < 3; ++b) {
    INFO("border " << b << ": " << border_times[0][b] << " s, " << border_times[1][b] << " s, " << border_times[2][b] << " s");
    CHECK(std::fabs(border_times[1][b] - border_times[0][b]) <= 0.45);
    CHECK(std::fabs(border_times[2][b] - border_times[0][b]) <= 0.45);
    CHECK(std::fabs(border_times[0][b] - ends[b]) <= 0.45);
  }
}

TEST_CASE("GIVEN a window in seconds WHEN frames arrive THEN it holds the last window_s of them, bounded in frames",
          "[segmentation][time]") {
  TableSimilarity similarity([](int, int) { return 0.5; });
  FiedlerSegmenterConfig config;
  config.window_s = 2.0;
  config.window = 50;
  config.min_window_frames = 4;
  FiedlerSegmenter segmenter(config, similarity);
  // 10 fps: frames less than 2 s old, i.e. 20.
  for (int k = 0; k < 40; ++k) segmenter.addFrame(k, 0.1 * k, fakeFingerprint(k));
  CHECK(segmenter.windowFrames() == 20);
  CHECK(segmenter.windowFull());
  // A gap of 10 s: the time rule would empty the window; it keeps min_window_frames.
  segmenter.addFrame(40, 14.0, fakeFingerprint(40));
  CHECK(segmenter.windowFrames() == 4);
  // 100 fps: the frame bound (50) wins.
  for (int k = 41; k < 200; ++k) segmenter.addFrame(k, 14.0 + 0.01 * (k - 40), fakeFingerprint(k));
  CHECK(segmenter.windowFrames() == 50);
}

TEST_CASE(
    "GIVEN blocks whose frames resemble their neighbours most WHEN the representative is the place medoid "
    "THEN each place is represented by its middle frame",
    "[segmentation][segmenter][medoid]") {
  // Inside a block the similarity falls with the distance in frames, so the frame most like the rest is
  // the middle one (of 30: frames 14 and 15 tie, the earlier wins). The thesis' window degree picks a
  // frame near the end instead: its window, looking back, lies wholly in the block.
  const std::vector<int> labels = blockLabels({30, 30, 30});
  TableSimilarity similarity([&](int a, int b) {
    if (labels[static_cast<std::size_t>(a)] != labels[static_cast<std::size_t>(b)]) return 0.05;
    return 0.95 - 0.01 * std::abs(a - b);
  });
  FiedlerSegmenterConfig config = thesisConfig();
  config.representative = RepresentativeChoice::PlaceMedoid;
  config.representative_interval_s = 0.0;  // every frame
  FiedlerSegmenter segmenter(config, similarity);
  const Run run = runStream(segmenter, 90);
  REQUIRE(run.places.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    INFO("place " << i);
    CHECK(run.places[i].first_frame == static_cast<std::int64_t>(30 * i));
    CHECK(run.places[i].last_frame == static_cast<std::int64_t>(30 * i + 29));
    CHECK(run.places[i].representative_frame == static_cast<std::int64_t>(30 * i + 14));
    // Sum over the 29 others of 0.95 - 0.01 |a - b|: 29 * 0.95 - 0.01 * (105 + 120).
    CHECK(run.places[i].representative_degree == Approx(29 * 0.95 - 2.25).margin(1e-9));
  }
  AND_WHEN("the same stream goes through the thesis' window degree") {
    FiedlerSegmenter thesis(thesisConfig(), similarity);
    const Run window_run = runStream(thesis, 90);
    REQUIRE(window_run.places.size() == 3);
    THEN("past the first place (whose window was still filling), its representatives are not the middle frames") {
      for (std::size_t i = 1; i < 3; ++i) CHECK(window_run.places[i].representative_frame != run.places[i].representative_frame);
    }
  }
}

TEST_CASE(
    "GIVEN a place longer than the samples kept WHEN the representative is the place medoid THEN the samples are "
    "thinned evenly and the medoid stays in the middle",
    "[segmentation][segmenter][medoid]") {
  const std::vector<int> labels = blockLabels({300, 60});
  TableSimilarity similarity([&](int a, int b) {
    if (labels[static_cast<std::size_t>(a)] != labels[static_cast<std::size_t>(b)]) return 0.05;
    return 0.95 - 0.002 * std::abs(a - b);
  });
  FiedlerSegmenterConfig config = thesisConfig();
  config.representative = RepresentativeChoice::PlaceMedoid;
  config.representative_interval_s = 0.2;  // = the stream's frame interval: every frame until thinned
  FiedlerSegmenter segmenter(config, similarity);
  const Run run = runStream(segmenter, 360);
  REQUIRE(run.places.size() == 2);
  CHECK(run.places[0].last_frame == 299);
  // 300 frames through 64 slots: thinned to every 8th frame (0, 8, ..., 296), whose middle is 144 or 152.
  CHECK(run.places[0].representative_frame % 8 == 0);
  CHECK(std::abs(run.places[0].representative_frame - 150) <= 8);
  THEN("the next place, sampled coarsely until the first one closed and densely after, keeps its medoid in the "
       "middle (each sample weighs the frames it stands for)") {
    CHECK(run.places[1].first_frame == 300);
    CHECK(std::abs(run.places[1].representative_frame - 330) <= 4);
  }
}

TEST_CASE("GIVEN representative settings WHEN validated or parsed THEN bad ones are refused by name",
          "[segmentation][segmenter][medoid]") {
  FiedlerSegmenterConfig config;
  config.representative_interval_s = -1.0;
  CHECK_THAT(config.validate(), Catch::Contains("representative_interval_s"));
  CHECK(parseRepresentativeChoice("place-medoid") == RepresentativeChoice::PlaceMedoid);
  CHECK(std::string(toString(RepresentativeChoice::WindowDegree)) == "window-degree");
  CHECK_THROWS_WITH(parseRepresentativeChoice("middle"), Catch::Contains("window-degree or place-medoid"));
}

TEST_CASE(
    "GIVEN place samples WHEN a place closes THEN it carries that many other keypoint-rich frames of it, spread "
    "over the place",
    "[segmentation][segmenter][samples]") {
  const std::vector<int> labels = blockLabels({30, 30, 30});
  TableSimilarity similarity([&](int a, int b) {
    return labels[static_cast<std::size_t>(a)] == labels[static_cast<std::size_t>(b)] ? 0.9 : 0.05;
  });
  FiedlerSegmenterConfig config = thesisConfig();
  config.place_samples = 3;  // at most one per 0.5 s: every third frame at 5 fps
  FiedlerSegmenter segmenter(config, similarity);
  // Odd frames have 5 keypoints (below min_keypoints): never a sample.
  const Run run = runStream(segmenter, 90, [](int f) { return f % 2 == 0 ? 50 : 5; });
  REQUIRE(run.places.size() == 3);
  for (const SegmentedPlace& place : run.places) {
    INFO("place " << place.first_frame << ".." << place.last_frame);
    REQUIRE(place.sample_count == 3);
    std::vector<int> ids;
    for (int k = 0; k < place.sample_count; ++k) ids.push_back(place.samples[static_cast<std::size_t>(k)]->image_width);
    CHECK(std::is_sorted(ids.begin(), ids.end()));
    for (int id : ids) {
      CHECK(id >= place.first_frame);
      CHECK(id <= place.last_frame);
      CHECK(id != place.representative_frame);
      CHECK(id % 2 == 0);
    }
    // Spread: one in each third of the place.
    const double third = (place.last_frame - place.first_frame + 1) / 3.0;
    CHECK(ids[0] < place.first_frame + third);
    CHECK(ids[2] >= place.first_frame + 2 * third);
    for (int k = 3; k < FiedlerSegmenterConfig::kMaxQuerySamples; ++k) CHECK(place.samples[static_cast<std::size_t>(k)] == nullptr);
  }
  AND_WHEN("place samples are off (the thesis)") {
    FiedlerSegmenter thesis(thesisConfig(), similarity);
    const Run off = runStream(thesis, 90);
    THEN("the places are the same and carry none") {
      REQUIRE(off.places.size() == 3);
      for (std::size_t i = 0; i < 3; ++i) {
        CHECK(off.places[i].sample_count == 0);
        CHECK(off.places[i].last_frame == run.places[i].last_frame);
      }
    }
  }
  config.place_samples = FiedlerSegmenterConfig::kMaxQuerySamples + 1;
  CHECK_THROWS_WITH(FiedlerSegmenter(config, similarity), Catch::Contains("place_samples: 17 is outside the allowed range [0, 16]"));
}
