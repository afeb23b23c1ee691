// The stage adapters of src/pipeline/algorithm_stages.cpp, each alone: VpackFingerprintStage (the
// fingerprint is the extractor's; the place-event thumbnail is made here, from the frame it was given),
// FiedlerSegmentationStage (a closed place carries its representative's thumbnail) and
// ParticleFilterTopologyStage (its one queue of places: each comes back whole with the filter's decision,
// numbered by the filter, also after a resumed map; advance() stops when its budget is spent, and slicing
// changes no decision).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <unistd.h>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "../segmentation/fake_similarity.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/pipeline/clock.hpp"

using namespace toposlam;

namespace {

/// A 320x240 BGR frame of vertical stripes (the extractor finds edges and keypoints in it) whose columns
/// alternate between two values, so that halving its width by pixel-area averaging gives their mean.
cv::Mat stripedFrame() {
  cv::Mat frame(240, 320, CV_8UC3);
  for (int x = 0; x < frame.cols; ++x) {
    const bool dark_stripe = (x / 40) % 2 == 1;
    const int base = dark_stripe ? 20 : 180;
    const cv::Scalar colour(base + (x % 2) * 40, base / 2 + (x % 2) * 20, 90 + (x % 2) * 60);
    frame.col(x).setTo(colour);
  }
  // Corners for the keypoint detector.
  for (int y = 20; y < 220; y += 50)
    for (int x = 10; x < 310; x += 60)
      cv::rectangle(frame, cv::Rect(x, y, 12, 12), cv::Scalar(255, 255, 255), cv::FILLED);
  return frame;
}

}  // namespace

TEST_CASE("GIVEN a 320x240 frame WHEN the fingerprint stage makes a 160-pixel thumbnail THEN it is 160x120, "
          "pixel-area averaged, and the fingerprint is the extractor's",
          "[pipeline][stages][thumbnail]") {
  const cv::Mat frame = stripedFrame();
  VpackFingerprintStage stage(VpackConfig{}, nullptr, 160);
  const FingerprintedFrame out = stage.process(frame, cv::Mat());

  REQUIRE(out.thumbnail.cols == 160);
  REQUIRE(out.thumbnail.rows == 120);
  REQUIRE(out.thumbnail.type() == CV_8UC3);
  // Column pairs (2k, 2k+1) of a bright stripe are (180, 90, 90) and (220, 110, 150): their mean.
  CHECK(out.thumbnail.at<cv::Vec3b>(0, 0) == cv::Vec3b(200, 100, 120));
  // Of a dark stripe (x 40..79 -> thumbnail 20..39): (20, 10, 90) and (60, 30, 150).
  CHECK(out.thumbnail.at<cv::Vec3b>(0, 25) == cv::Vec3b(40, 20, 120));
  cv::Mat expected;
  cv::resize(frame, expected, cv::Size(160, 120), 0, 0, cv::INTER_AREA);
  CHECK(cv::norm(out.thumbnail, expected, cv::NORM_INF) == 0.0);
  // The thumbnail is a copy: the frame's buffer may go back to the source.
  CHECK(out.thumbnail.data != frame.data);

  const Fingerprint alone = VpackExtractor(VpackConfig{}).extract(frame);
  CHECK(alone.keypointCount() > 0);
  CHECK(alone.edge_columns.size() >= 4);
  CHECK(out.fingerprint.equals(alone));
}

TEST_CASE("GIVEN frames of other sizes WHEN thumbnails are made THEN the height keeps the aspect (at "
          "least 1) and a frame narrower than the width is not enlarged",
          "[pipeline][stages][thumbnail]") {
  VpackFingerprintStage stage(VpackConfig{}, nullptr, 160);
  cv::Mat frame333;
  cv::resize(stripedFrame(), frame333, cv::Size(333, 100));
  const FingerprintedFrame a = stage.process(frame333, cv::Mat());
  CHECK(a.thumbnail.cols == 160);
  CHECK(a.thumbnail.rows == 48);  // 100 * 160 / 333 = 48.05

  cv::Mat small;
  cv::resize(stripedFrame(), small, cv::Size(64, 48), 0, 0, cv::INTER_AREA);
  const FingerprintedFrame b = stage.process(small, cv::Mat());
  REQUIRE(b.thumbnail.size() == cv::Size(64, 48));
  CHECK(cv::norm(b.thumbnail, small, cv::NORM_INF) == 0.0);

  VpackFingerprintStage narrow(VpackConfig{}, nullptr, 16);
  cv::Mat strip;
  cv::resize(stripedFrame(), strip, cv::Size(1000, 16));
  const FingerprintedFrame c = narrow.process(strip, cv::Mat());
  CHECK(c.thumbnail.size() == cv::Size(16, 1));  // 16 * 16 / 1000 rounds to 0: one row
}

TEST_CASE("GIVEN a grey camera frame WHEN the thumbnail is made THEN it is grey too",
          "[pipeline][stages][thumbnail]") {
  cv::Mat grey;
  cv::cvtColor(stripedFrame(), grey, cv::COLOR_BGR2GRAY);
  VpackFingerprintStage stage(VpackConfig{}, nullptr, 80);
  const FingerprintedFrame out = stage.process(grey, grey);
  REQUIRE(out.thumbnail.type() == CV_8UC1);
  CHECK(out.thumbnail.size() == cv::Size(80, 60));
}

TEST_CASE("GIVEN the offline commands' stage (no thumbnail) WHEN a frame is processed THEN the thumbnail is "
          "empty and the fingerprint the same",
          "[pipeline][stages][thumbnail]") {
  const cv::Mat frame = stripedFrame();
  VpackFingerprintStage offline(VpackConfig{}, nullptr);
  VpackFingerprintStage daemon(VpackConfig{}, nullptr, 160);
  const FingerprintedFrame a = offline.process(frame, cv::Mat());
  CHECK(a.thumbnail.empty());
  CHECK(a.fingerprint.equals(daemon.process(frame, cv::Mat()).fingerprint));
}

namespace {

/// Fingerprint ids 1 and 3 look alike, 2 looks like neither.
double firstAndThirdAlike(int a, int b) { return a == b || a + b == 4 ? 0.95 : 0.05; }

/// TableSimilarity's fingerprint `id` (its image width), valid enough to go through a map file: one
/// subregion over a one-row image, no keypoints.
std::shared_ptr<const Fingerprint> placeFingerprint(int id) {
  auto f = std::make_shared<Fingerprint>();
  f->image_width = id;
  f->image_height = 1;
  f->subregions.push_back(Subregion{0, id, {}, 0, 0});
  return f;
}

TopologyFilterConfig smallFilter() {
  TopologyFilterConfig c;
  c.particles = 100;
  c.likelihood = LikelihoodModel::Relative;
  return c;
}

/// A closed place of frames [first, first + 9] represented by fingerprint `id`, its thumbnail one pixel of
/// value 100 + id.
ClosedPlace closedPlace(int index, int id, std::int64_t first) {
  ClosedPlace p;
  p.place = index;
  p.first_frame = first;
  p.last_frame = first + 9;
  p.representative_frame = first + 4;
  p.keypoints = 50;
  p.representative = placeFingerprint(id);
  p.thumbnail = cv::Mat(1, 1, CV_8UC3, cv::Scalar::all(100 + id));
  return p;
}

/// Runs the queued steps to their end; the places in the order they finished.
std::vector<FinishedPlace> finishAll(ParticleFilterTopologyStage& stage,
                                     std::vector<std::size_t>* queued = nullptr) {
  std::vector<FinishedPlace> finished;
  while (!stage.idle())
    if (std::optional<FinishedPlace> done = stage.advance(1e9)) {
      finished.push_back(std::move(*done));
      if (queued != nullptr) queued->push_back(stage.queuedPlaces());
    }
  return finished;
}

}  // namespace

TEST_CASE("GIVEN three closed places, the third like the first WHEN the topology stage steps them THEN each "
          "comes back whole from its one queue, in order, with the filter's decision",
          "[pipeline][stages][topology]") {
  const test::TableSimilarity similarity(firstAndThirdAlike);
  ManualClock clock;
  ParticleFilterTopologyStage stage(smallFilter(), similarity, clock, {64, 3});
  REQUIRE(stage.idle());
  for (int i = 0; i < 3; ++i) stage.enqueuePlace(closedPlace(i, i + 1, 10 * i));
  CHECK(stage.queuedPlaces() == 3);
  CHECK_FALSE(stage.idle());

  std::vector<std::size_t> queued_after;
  const std::vector<FinishedPlace> finished = finishAll(stage, &queued_after);
  REQUIRE(finished.size() == 3);
  CHECK(queued_after == std::vector<std::size_t>{2, 1, 0});
  for (int i = 0; i < 3; ++i) {
    const FinishedPlace& f = finished[static_cast<std::size_t>(i)];
    CHECK(f.assignment.place == i);
    CHECK(f.place.place == i);
    CHECK(f.place.first_frame == 10 * i);
    CHECK(f.place.last_frame == 10 * i + 9);
    CHECK(f.place.representative_frame == 10 * i + 4);
    REQUIRE(f.place.thumbnail.size() == cv::Size(1, 1));
    CHECK(f.place.thumbnail.at<cv::Vec3b>(0, 0)[0] == 101 + i);
    REQUIRE(f.place.representative != nullptr);
    CHECK(f.place.representative->image_width == i + 1);
  }
  // Two rooms: the third place is a revisit of the first.
  CHECK(finished[0].assignment.node == 0);
  CHECK(finished[0].assignment.is_new);
  CHECK(finished[1].assignment.node == 1);
  CHECK(finished[1].assignment.is_new);
  CHECK(finished[2].assignment.node == 0);
  CHECK_FALSE(finished[2].assignment.is_new);
  CHECK(finished[2].assignment.probability > 0.5);

  const PlaceEstimate& e = stage.estimate();
  CHECK(e.place == 2);
  CHECK(e.node == 0);
  CHECK(e.map_revision == 3);
  const TopologySnapshot t = stage.topology();
  REQUIRE(t.nodes.size() == 2);
  CHECK(t.nodes[0].places == std::vector<int>{0, 2});
  CHECK(t.nodes[0].representative_frames == std::vector<std::int64_t>{4, 24});
  CHECK(t.nodes[1].places == std::vector<int>{1});
  REQUIRE(t.edges.size() == 2);
  CHECK((t.edges[0].from == 0 && t.edges[0].to == 1 && t.edges[0].count == 1));
  CHECK((t.edges[1].from == 1 && t.edges[1].to == 0 && t.edges[1].count == 1));

  // A frame's match is named by the stepped place holding it and that place's node (place_t.match_*).
  const auto located = [&](std::int64_t frame) {
    RevisitEstimate r;
    r.match_frame = frame;
    stage.locate(r);
    return std::make_pair(r.match_place, r.match_node);
  };
  CHECK(located(3) == std::make_pair(0, 0));
  CHECK(located(19) == std::make_pair(1, 1));
  CHECK(located(25) == std::make_pair(2, 0));  // the revisit: the first place's node
  CHECK(located(30) == std::make_pair(-1, -1));  // after the last stepped place
  CHECK(located(-1) == std::make_pair(-1, -1));  // no match
}

TEST_CASE("GIVEN a map of three places saved and loaded WHEN a new run's first place is stepped THEN the "
          "filter numbers it 3, and the place comes back numbered so",
          "[pipeline][stages][topology]") {
  const test::TableSimilarity similarity(firstAndThirdAlike);
  ManualClock clock;
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("toposlam-stages-" + std::to_string(::getpid()) + ".tsm");
  {
    ParticleFilterTopologyStage first_run(smallFilter(), similarity, clock, {64, 3});
    for (int i = 0; i < 3; ++i) first_run.enqueuePlace(closedPlace(i, i + 1, 10 * i));
    REQUIRE(finishAll(first_run).size() == 3);
    first_run.snapshotMap()->writeTo(path.string());
  }
  ParticleFilterTopologyStage resumed(smallFilter(), similarity, clock, {64, 3});
  resumed.loadMap(path.string());
  std::filesystem::remove(path);
  CHECK(resumed.observations() == 3);
  resumed.enqueuePlace(closedPlace(0, 2, 0));  // the segmentation's place 0 of this run, like place 1
  const std::vector<FinishedPlace> finished = finishAll(resumed);
  REQUIRE(finished.size() == 1);
  CHECK(finished[0].assignment.place == 3);
  CHECK(finished[0].place.place == 3);
  CHECK(finished[0].assignment.node == 1);
  CHECK_FALSE(finished[0].assignment.is_new);
  // Representative frames of the older run mean nothing in this one: -1.
  const TopologySnapshot t = resumed.topology();
  REQUIRE(t.nodes.size() == 2);
  CHECK(t.nodes[1].places == std::vector<int>{1, 3});
  CHECK(t.nodes[1].representative_frames == std::vector<std::int64_t>{-1, 4});
  // Frames are this run's: the new place's frames name it, the older run's frames are not known.
  RevisitEstimate r;
  r.match_frame = 5;
  resumed.locate(r);
  CHECK((r.match_place == 3 && r.match_node == 1));
  r.match_frame = 25;
  resumed.locate(r);
  CHECK((r.match_place == -1 && r.match_node == -1));
}

TEST_CASE("GIVEN frames with thumbnails WHEN the segmentation stage closes a place THEN it carries its "
          "representative frame's thumbnail",
          "[pipeline][stages][segmentation]") {
  // Two blocks of 40 near-identical frames.
  const test::TableSimilarity similarity(
      [](int a, int b) { return a / 40 == b / 40 ? 0.9 + 0.05 * std::sin(0.7 * a + 1.3 * b) : 0.05; });
  FiedlerSegmenterConfig config;
  config.window = 20;
  FiedlerSegmentationStage stage(config, similarity);
  std::vector<ClosedPlace> closed;
  for (int f = 0; f < 80; ++f) {
    const cv::Mat thumbnail(1, 1, CV_16UC1, cv::Scalar(1000 + f));
    SegmentationStep step = stage.process(f, 0.2 * f, 0.2 * f, test::fakeFingerprint(f), thumbnail);
    if (step.closed) closed.push_back(std::move(*step.closed));
  }
  if (std::optional<ClosedPlace> last = stage.finish()) closed.push_back(std::move(*last));
  REQUIRE(closed.size() == 2);
  for (std::size_t p = 0; p < closed.size(); ++p) {
    const ClosedPlace& place = closed[p];
    CHECK(place.place == static_cast<int>(p));
    CHECK(place.first_frame <= place.representative_frame);
    CHECK(place.representative_frame <= place.last_frame);
    REQUIRE(place.thumbnail.size() == cv::Size(1, 1));
    CHECK(place.thumbnail.at<std::uint16_t>(0, 0) == 1000 + place.representative_frame);
  }
  CHECK(closed[0].first_frame == 0);
  CHECK(closed[1].last_frame == 79);
}

namespace {

/// A clock that moves one tick (2^-10 s, about 1 ms: exact in binary, so no rounding decides a comparison)
/// each time it is read: the topology stage's budget counts its own readings.
class TickingClock final : public Clock {
 public:
  static constexpr double kTick = 1.0 / 1024.0;
  double now() const override { return kTick * static_cast<double>(readings_++); }
  std::int64_t readings() const { return readings_; }

 private:
  mutable std::int64_t readings_ = 0;
};

}  // namespace

TEST_CASE("GIVEN a budget of 3 ticks on a clock that ticks each reading WHEN the topology stage advances "
          "THEN each call stops after 3 slices, a step takes many calls, and the decisions are unchanged",
          "[pipeline][stages][topology]") {
  const test::TableSimilarity similarity(firstAndThirdAlike);
  TickingClock ticking;
  ManualClock still;
  ParticleFilterTopologyStage sliced(smallFilter(), similarity, ticking, {8, 3});
  ParticleFilterTopologyStage whole(smallFilter(), similarity, still, {8, 3});
  for (int i = 0; i < 3; ++i) {
    sliced.enqueuePlace(closedPlace(i, i + 1, 10 * i));
    whole.enqueuePlace(closedPlace(i, i + 1, 10 * i));
  }
  std::vector<FinishedPlace> from_sliced;
  int calls = 0, calls_cut_by_budget = 0;
  while (!sliced.idle()) {
    const std::int64_t readings_before = ticking.readings();
    std::optional<FinishedPlace> done = sliced.advance(3 * TickingClock::kTick);
    ++calls;
    if (done) {
      from_sliced.push_back(std::move(*done));
    } else {
      // One reading for the deadline, one after each slice: 3 slices, then the budget is spent.
      CHECK(ticking.readings() - readings_before == 4);
      ++calls_cut_by_budget;
    }
  }
  const std::vector<FinishedPlace> from_whole = finishAll(whole);
  REQUIRE(from_sliced.size() == 3);
  REQUIRE(from_whole.size() == 3);
  CHECK(calls == calls_cut_by_budget + 3);
  // 100 particles, 8 work items a slice, 3 slices a call: 24 calls the budget cut short over the 3 steps.
  CHECK(calls_cut_by_budget == 24);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(from_sliced[i].assignment.node == from_whole[i].assignment.node);
    CHECK(from_sliced[i].assignment.is_new == from_whole[i].assignment.is_new);
    CHECK(from_sliced[i].assignment.probability == from_whole[i].assignment.probability);
  }
  CHECK(sliced.topology().probability == whole.topology().probability);
}
