// Place recognition on the two bundled real sets, as `toposlam recognition` measures it
// (docs/matching.md, "Real images"): the default similarity must keep its figures (with a margin), the
// thesis preset must reproduce the published method's, and both are reported beside the plain ORB
// baseline of the same run. A change that makes real-image recognition worse fails here.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "camera_pixels.hpp"
#include "toposlam/eval/orb_baseline.hpp"
#include "toposlam/eval/recognition.hpp"
#include "toposlam/eval/ground_truth.hpp"
#include "toposlam/io/file_sources.hpp"
#include "toposlam/matching/labelled_image_list.hpp"
#include "toposlam/matching/place_localizer.hpp"
#include "toposlam/matching/place_route_filter.hpp"
#include "toposlam/matching/sequence_similarity.hpp"
#include "toposlam/matching/similarity_preset.hpp"

using namespace toposlam;
using toposlam::bgrToYuyv;
using toposlam::CameraImages;
using toposlam::CameraPixelLayout;

namespace {

struct Frames {
  std::vector<std::string> paths;
  std::vector<cv::Mat> images;
};

Frames readFolder(const std::string& folder) {
  Frames f;
  f.paths = listImageFiles(folder);
  for (const auto& p : f.paths) {
    f.images.push_back(cv::imread(p, cv::IMREAD_COLOR));
    REQUIRE_FALSE(f.images.back().empty());
  }
  return f;
}

std::vector<std::uint8_t> samePairs(const std::string& pairs_file, const Frames& queries, const Frames& references,
                                    bool symmetric) {
  std::vector<std::uint8_t> same(queries.paths.size() * references.paths.size(), 0);
  for (const eval::NamedPair& p : eval::loadLoopClosurePairs(pairs_file)) {
    const int q = eval::resolveFrameName(p.query, queries.paths);
    const int r = eval::resolveFrameName(p.match, references.paths);
    REQUIRE(q >= 0);
    REQUIRE(r >= 0);
    same[static_cast<std::size_t>(q) * references.paths.size() + static_cast<std::size_t>(r)] = 1;
    if (symmetric) same[static_cast<std::size_t>(r) * references.paths.size() + static_cast<std::size_t>(q)] = 1;
  }
  return same;
}

eval::RecognitionTruth samplesTruth(const Frames& frames) {
  eval::LoopClosureMatrix m;
  m.size = static_cast<int>(frames.paths.size());
  m.same = samePairs(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples_GT_pairs.csv", frames, frames, true);
  return eval::sequenceTruthFromMatrix(m, 10);
}

// Fills every candidate cell with similarity(query i, reference j), scored as sequences of
// `sequence_length` frames (1: each frame on its own), and scores the matrix.
template <typename Similarity>
eval::RecognitionScore scoreMatrix(const eval::RecognitionTruth& truth, Similarity similarity, int sequence_length) {
  std::vector<float> s(truth.state.size(), 0.f);
  std::vector<std::uint8_t> candidate(truth.state.size(), 0);
  for (int i = 0; i < truth.queries; ++i)
    for (int j = 0; j < truth.references; ++j)
      if (truth.at(i, j) >= 0) {
        s[static_cast<std::size_t>(i * truth.references + j)] = static_cast<float>(similarity(i, j));
        candidate[static_cast<std::size_t>(i * truth.references + j)] = 1;
      }
  return eval::scoreRecognition(sequenceSimilarity(s, candidate, truth.queries, truth.references, sequence_length), truth);
}

eval::RecognitionScore scoreOurs(const std::string& preset_name, const Frames& queries, const Frames& references,
                                 const eval::RecognitionTruth& truth, int sequence_length = 1, int max_keypoints = -1) {
  const SimilarityPreset preset = similarityPreset(preset_name);
  VpackConfig vpack = preset.fingerprint;
  if (max_keypoints > 0) vpack.keypoints.setMaxKeypoints(max_keypoints);  // as `recognition --max-keypoints`
  const VpackExtractor extractor(vpack);
  const NgramSimilarity similarity(preset.similarity);
  std::vector<Fingerprint> q, r;
  for (const cv::Mat& image : queries.images) q.push_back(extractor.extract(image));
  for (const cv::Mat& image : references.images) r.push_back(extractor.extract(image));
  return scoreMatrix(truth, [&](int i, int j) {
    return similarity.symmetricSimilarity(r[static_cast<std::size_t>(j)], q[static_cast<std::size_t>(i)]);
  }, sequence_length);
}

eval::RecognitionScore scoreBaseline(const Frames& queries, const Frames& references, const eval::RecognitionTruth& truth,
                                     int sequence_length = 1, int keypoints = 100) {
  eval::OrbBaselineConfig baseline_config;
  baseline_config.keypoints = keypoints;
  const eval::OrbBaseline baseline(baseline_config);
  std::vector<cv::Mat> q, r;
  for (const cv::Mat& image : queries.images) q.push_back(baseline.extract(image));
  for (const cv::Mat& image : references.images) r.push_back(baseline.extract(image));
  return scoreMatrix(truth, [&](int i, int j) {
    return baseline.similarity(r[static_cast<std::size_t>(j)], q[static_cast<std::size_t>(i)]);
  }, sequence_length);
}

// The corridor set (Milford 2013, via VPR-Bench): 111 query frames against 111 reference frames.
struct CorridorSet {
  Frames references;
  Frames queries;
  eval::RecognitionTruth truth;
};

CorridorSet readCorridor() {
  const std::string dir = TOPOSLAM_CORRIDOR_DIR;
  CorridorSet set{readFolder(dir + "/ref"), readFolder(dir + "/query"), {}};
  REQUIRE(set.references.paths.size() == 111);
  REQUIRE(set.queries.paths.size() == 111);
  set.truth = eval::crossTruth(111, 111, samePairs(dir + "/gt.csv", set.queries, set.references, false));
  return set;
}

std::string figures(const eval::RecognitionScore& s) {
  return "AUC " + std::to_string(s.auc) + ", top-1 " + std::to_string(s.top1) + ", recall@100%P " +
         std::to_string(s.recall_at_full_precision);
}

struct CameraPathScore {
  eval::RecognitionScore via_bgr;    ///< YUYV -> BGR -> grey for edges and keypoints (before issue 18)
  eval::RecognitionScore via_luma;   ///< YUYV -> BGR for histograms, the luma for edges and keypoints
  int frames = 0, identical = 0;     ///< fingerprints equal to the bit either way
  double edge_difference = 0.0;      ///< mean |edges via luma - edges via BGR| per frame
  double keypoint_difference = 0.0;  ///< mean |keypoints via luma - via BGR| per frame
};

// Both camera paths of the default preset over a query and a reference set, scored against `truth`.
CameraPathScore scoreCameraPaths(const Frames& queries, const Frames& references,
                                 const eval::RecognitionTruth& truth, bool one_set) {
  const SimilarityPreset preset = similarityPreset("default");
  const VpackExtractor extractor(preset.fingerprint);
  const NgramSimilarity similarity(preset.similarity);
  CameraPathScore out;
  auto fingerprint = [&](const Frames& set, std::vector<Fingerprint>& via_bgr,
                         std::vector<Fingerprint>& via_luma) {
    for (const cv::Mat& image : set.images) {
      const std::vector<std::uint8_t> yuyv = bgrToYuyv(image);  // as a YUYV camera delivers it
      const std::size_t stride = static_cast<std::size_t>(image.cols) * 2;
      via_bgr.push_back(extractor.extract(cameraBufferToBgr(CameraPixelLayout::Yuyv, yuyv.data(), yuyv.size(),
                                                            image.cols, image.rows, stride)));
      const CameraImages camera = cameraBufferToImages(CameraPixelLayout::Yuyv, yuyv.data(), yuyv.size(),
                                                       image.cols, image.rows, stride);
      via_luma.push_back(extractor.extract(camera.image, camera.grey));
      ++out.frames;
      out.identical += via_bgr.back().equals(via_luma.back()) ? 1 : 0;
      out.edge_difference += std::abs(static_cast<double>(via_bgr.back().edge_columns.size()) -
                                      static_cast<double>(via_luma.back().edge_columns.size()));
      out.keypoint_difference += std::abs(via_bgr.back().keypointCount() - via_luma.back().keypointCount());
    }
  };
  std::vector<Fingerprint> q_bgr, q_luma, r_bgr, r_luma;
  fingerprint(queries, q_bgr, q_luma);
  if (!one_set) fingerprint(references, r_bgr, r_luma);
  const std::vector<Fingerprint>& rb = one_set ? q_bgr : r_bgr;
  const std::vector<Fingerprint>& rl = one_set ? q_luma : r_luma;
  out.via_bgr = scoreMatrix(
      truth,
      [&](int i, int j) {
        return similarity.symmetricSimilarity(rb[static_cast<std::size_t>(j)],
                                              q_bgr[static_cast<std::size_t>(i)]);
      },
      1);
  out.via_luma = scoreMatrix(
      truth,
      [&](int i, int j) {
        return similarity.symmetricSimilarity(rl[static_cast<std::size_t>(j)],
                                              q_luma[static_cast<std::size_t>(i)]);
      },
      1);
  out.edge_difference /= out.frames;
  out.keypoint_difference /= out.frames;
  return out;
}

}  // namespace

SCENARIO("GIVEN the bundled corridor loop WHEN each frame is recognised among its past THEN the default keeps its figures", "[real]") {
  const Frames frames = readFolder(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples");
  REQUIRE(frames.paths.size() == 84);
  const eval::RecognitionTruth truth = samplesTruth(frames);
  const eval::RecognitionScore ours = scoreOurs("default", frames, frames, truth);
  const eval::RecognitionScore baseline = scoreBaseline(frames, frames, truth);
  INFO("default: " << figures(ours) << "; ORB baseline: " << figures(baseline));
  REQUIRE(ours.queries_with_match == 44);
  // Measured: 0.851 / 0.977 (43 of 44) / 0.955; baseline 0.880 / 0.977 / 0.977.
  CHECK(ours.auc >= 0.83);
  CHECK(ours.top1 >= 0.95);
  CHECK(ours.recall_at_full_precision >= 0.93);
  CHECK(baseline.top1 >= 0.95);
}

SCENARIO("GIVEN the bundled corridor loop WHEN the thesis preset is used THEN it reproduces the published method's figures", "[real]") {
  const Frames frames = readFolder(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples");
  const eval::RecognitionTruth truth = samplesTruth(frames);
  const eval::RecognitionScore thesis = scoreOurs("thesis", frames, frames, truth);
  INFO("thesis: " << figures(thesis));
  // Measured (and in issue 13's table): 0.733 / 0.705 (31 of 44) / 0.182.
  CHECK(thesis.auc == Approx(0.733).margin(0.01));
  CHECK(thesis.top1_correct == 31);
  CHECK(thesis.recall_at_full_precision == Approx(0.182).margin(0.03));
}

SCENARIO("GIVEN the fisheye corridor set WHEN queries are recognised among the references THEN the default beats the ORB baseline", "[real]") {
  const CorridorSet c = readCorridor();
  const eval::RecognitionScore ours = scoreOurs("default", c.queries, c.references, c.truth);
  const eval::RecognitionScore baseline = scoreBaseline(c.queries, c.references, c.truth);
  INFO("default: " << figures(ours) << "; ORB baseline: " << figures(baseline));
  // Measured: 0.854 / 0.514 / 0.027; baseline 0.646 / 0.297 / 0.000.
  CHECK(ours.auc >= 0.82);
  CHECK(ours.top1 >= 0.45);
  CHECK(ours.top1 >= baseline.top1 + 0.1);
  CHECK(ours.auc >= baseline.auc + 0.1);
}

namespace {

struct LocalisationFigures {
  int queries = 0;
  int correct = 0;
  int reached = 0;          ///< queries at p >= 0.5
  int correct_reached = 0;  ///< correct among them
  double precisionReached() const { return reached > 0 ? static_cast<double>(correct_reached) / reached : 0.0; }
};

// Localises a labelled query list among labelled places as `toposlam localize` does (default preset);
// with a route filter, the queries are one traversal in file order.
LocalisationFigures localiseList(const std::string& places_csv, const std::string& queries_csv,
                                 const PlaceRouteFilterConfig* route) {
  const LabelledImageList place_list = readLabelledImageList(places_csv);
  const LabelledImageList query_list = readLabelledImageList(queries_csv);
  const SimilarityPreset preset = similarityPreset("default");
  const VpackExtractor extractor(preset.fingerprint);
  std::vector<LabelledPlace> places;
  std::map<std::string, std::size_t> index;
  for (const LabelledImage& entry : place_list.images) {
    auto [it, inserted] = index.emplace(entry.label, places.size());
    if (inserted) places.push_back({entry.label, {}});
    places[it->second].references.push_back(extractor.extract(cv::imread(entry.path, cv::IMREAD_COLOR)));
  }
  PlaceLocalizerConfig config;
  config.similarity = preset.similarity;
  const PlaceLocalizer localizer(config, std::move(places));
  std::optional<PlaceRouteFilter> filter;
  if (route) filter.emplace(*route, localizer.placeCount());
  LocalisationFigures figures;
  for (const LabelledImage& entry : query_list.images) {
    const Localization l = localizer.localize(extractor.extract(cv::imread(entry.path, cv::IMREAD_COLOR)));
    const std::vector<double>& p = filter ? filter->update(l.probabilities) : l.probabilities;
    const auto best = std::max_element(p.begin(), p.end());
    const bool right = localizer.place(static_cast<int>(best - p.begin())).label == entry.label;
    ++figures.queries;
    figures.correct += right ? 1 : 0;
    if (*best >= 0.5) {
      ++figures.reached;
      figures.correct_reached += right ? 1 : 0;
    }
  }
  return figures;
}

std::string describe(const LocalisationFigures& f) {
  std::ostringstream out;
  out << f.correct << " of " << f.queries << " correct; " << f.reached << " at p >= 0.5, " << f.correct_reached
      << " of them correct";
  return out.str();
}

}  // namespace

SCENARIO("GIVEN the first traversal as places WHEN the second is localised with the default preset THEN Table 3.1 improves on the thesis' numbers", "[real]") {
  const std::string data = TOPOSLAM_SAMPLES_DIR;
  const LocalisationFigures f = localiseList(data + "/places.csv", data + "/queries.csv", nullptr);
  INFO(describe(f));
  REQUIRE(f.queries == 44);
  // Measured: 36 of 44 correct; 31 at p >= 0.5 with 87.1 % precision (thesis preset: 28; 28 at 78.6 %).
  CHECK(f.correct >= 34);
  CHECK(f.reached >= 28);
  CHECK(f.precisionReached() >= 0.84);
}

SCENARIO("GIVEN the second traversal in time order WHEN it is localised along the route THEN most queries are confident and right", "[real][route]") {
  const std::string data = TOPOSLAM_SAMPLES_DIR;
  const PlaceRouteFilterConfig route;  // stay 0.7, jump 0.01, loop: the samples' route is a loop
  const LocalisationFigures single = localiseList(data + "/places.csv", data + "/queries.csv", nullptr);
  const LocalisationFigures along = localiseList(data + "/places.csv", data + "/queries.csv", &route);
  INFO("along the route: " << describe(along) << "; single images: " << describe(single));
  // Measured: 39 of 44 correct; 43 at p >= 0.5 with 90.7 % (issue 13's target: >= 35 at >= 90 %).
  CHECK(along.correct >= 38);
  CHECK(along.reached >= 40);
  CHECK(along.precisionReached() >= 0.88);
  CHECK(along.reached >= single.reached + 8);
}

SCENARIO("GIVEN the corridor's reference lap as places WHEN the query lap is localised along the route THEN it beats single images by far", "[real][route]") {
  const std::string data = TOPOSLAM_CORRIDOR_DIR;
  PlaceRouteFilterConfig route;
  route.loop = false;  // one corridor, walked end to end
  const LocalisationFigures single = localiseList(data + "/places.csv", data + "/queries.csv", nullptr);
  const LocalisationFigures along = localiseList(data + "/places.csv", data + "/queries.csv", &route);
  INFO("along the route: " << describe(along) << "; single images: " << describe(single));
  REQUIRE(along.queries == 111);
  // Measured: 79 of 111 correct, 26 at p >= 0.5 with 96.2 %; single images 73 correct, none at 0.5.
  CHECK(along.correct >= single.correct + 3);
  CHECK(along.reached >= 20);
  CHECK(along.precisionReached() >= 0.9);
  CHECK(single.reached <= 3);
}

SCENARIO("GIVEN the fisheye corridor set WHEN queries are recognised as sequences of 10 frames THEN most find their "
         "place, far ahead of the ORB baseline scored the same way", "[real][sequence]") {
  const CorridorSet c = readCorridor();
  const eval::RecognitionScore single = scoreOurs("default", c.queries, c.references, c.truth, 1);
  const eval::RecognitionScore ours = scoreOurs("default", c.queries, c.references, c.truth, 10);
  const eval::RecognitionScore baseline = scoreBaseline(c.queries, c.references, c.truth, 10);
  INFO("default, sequences of 10: " << figures(ours) << "; single frames: " << figures(single)
                                    << "; ORB baseline, sequences of 10: " << figures(baseline));
  // Measured: 0.963 / 0.847 (94 of 111) / 0.162; single frames 0.854 / 0.514; baseline 0.787 / 0.532 / 0.054.
  CHECK(ours.auc >= 0.94);
  CHECK(ours.top1 >= 0.80);
  CHECK(ours.top1 >= single.top1 + 0.25);
  CHECK(ours.top1 >= baseline.top1 + 0.2);
}

SCENARIO("GIVEN the bundled corridor loop WHEN frames are recognised as sequences of 3 THEN every revisit ranks first",
         "[real][sequence]") {
  const Frames frames = readFolder(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples");
  const eval::RecognitionTruth truth = samplesTruth(frames);
  const eval::RecognitionScore ours = scoreOurs("default", frames, frames, truth, 3);
  const eval::RecognitionScore baseline = scoreBaseline(frames, frames, truth, 3);
  INFO("default, sequences of 3: " << figures(ours) << "; ORB baseline, sequences of 3: " << figures(baseline));
  // Measured: 0.951 / 1.000 (44 of 44) / 1.000; baseline 0.964 / 1.000 / 1.000.
  CHECK(ours.auc >= 0.92);
  CHECK(ours.top1_correct == 44);
  CHECK(ours.recall_at_full_precision >= 0.97);
}

SCENARIO("GIVEN the fisheye corridor set WHEN frames keep 200 keypoints and queries are scored as sequences of 10 THEN "
         "top-1 reaches 0.9, far ahead of the ORB baseline with the same budget", "[real][sequence]") {
  const CorridorSet c = readCorridor();
  const eval::RecognitionScore ours = scoreOurs("default", c.queries, c.references, c.truth, 10, 200);
  const eval::RecognitionScore baseline = scoreBaseline(c.queries, c.references, c.truth, 10, 200);
  INFO("default, 200 keypoints, sequences of 10: " << figures(ours) << "; ORB baseline, the same: " << figures(baseline));
  // Measured: 0.964 / 0.919 (102 of 111) / 0.243; baseline 0.862 / 0.532 / 0.108 (`toposlam recognition
  // --reference images:C/ref --query images:C/query --truth C/gt.csv --sequence 10 --max-keypoints 200`).
  CHECK(ours.auc >= 0.94);
  CHECK(ours.top1 >= 0.88);
  CHECK(ours.top1 >= baseline.top1 + 0.25);
}

SCENARIO(
    "GIVEN the real sets as a YUYV camera delivers them WHEN edges and keypoints take the camera's luma THEN "
    "recognition keeps the figures of the round trip through BGR",
    "[real][camera]") {
  // Issue 18: the luma is no longer made from the BGR image. The two greys differ where the decoder
  // clips a channel and by rounding, so a few fingerprints change; recognition must not.
  const Frames samples = readFolder(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples");
  const CameraPathScore loop = scoreCameraPaths(samples, samples, samplesTruth(samples), true);
  const CorridorSet c = readCorridor();
  const CameraPathScore corridor = scoreCameraPaths(c.queries, c.references, c.truth, false);
  for (const auto& [name, s] :
       {std::pair{"corridor loop", &loop}, std::pair{"fisheye corridor", &corridor}}) {
    INFO(name << ": via BGR " << figures(s->via_bgr) << "; via luma " << figures(s->via_luma) << "; "
              << s->identical << " of " << s->frames << " fingerprints identical, mean |edge difference| "
              << s->edge_difference << ", mean |keypoint difference| " << s->keypoint_difference);
    CHECK(std::abs(s->via_luma.auc - s->via_bgr.auc) <= 0.01);
    CHECK(s->via_luma.top1 >= s->via_bgr.top1);
    CHECK(s->via_luma.recall_at_full_precision >= s->via_bgr.recall_at_full_precision);
    CHECK(s->edge_difference <= 0.05);
    CHECK(s->keypoint_difference <= 3.0);
  }
  // Measured (docs/performance.md): corridor loop via BGR 0.845 / 0.977 / 0.955, via luma 0.840 / 0.977
  // / 0.977, 2 of 84 fingerprints identical, 0.024 edges and 1.75 keypoints apart per frame; fisheye
  // corridor 0.861 / 0.568 / 0.009 and 0.857 / 0.577 / 0.027, 0 of 222 identical, 0.005 and 1.98.
  CHECK(loop.via_luma.auc == Approx(0.8395).margin(0.002));
  CHECK(corridor.via_luma.auc == Approx(0.8569).margin(0.002));
}
