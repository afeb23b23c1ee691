// `toposlam recognition`: place recognition measured on its own (docs/evaluation.md, "Place
// recognition"). Fingerprints a sequence (or a query set and a reference set), computes the similarity
// of every candidate pair, and scores it against a ground truth: AUC, top-1 and recall at 100 %
// precision. A plain OpenCV ORB baseline with the same keypoint budget runs on the same frames in the
// same run, so every figure has its baseline beside it. With --out: similarity matrices (CSV), heat maps
// (PNG) and the precision-recall curves (SVG), plus recognition.json.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "commands.hpp"
#include "progress.hpp"
#include "image_input.hpp"
#include "offline_run_io.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/platform/output_file.hpp"
#include "toposlam/core/svg_plot.hpp"
#include "toposlam/eval/evaluation.hpp"
#include "toposlam/eval/orb_baseline.hpp"
#include "toposlam/eval/recognition.hpp"
#include "toposlam/eval/report.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/io/file_sources.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/matching/sequence_similarity.hpp"
#include "toposlam/matching/similarity_preset.hpp"

namespace toposlam::cli {
namespace {

namespace fs = std::filesystem;

struct RecognitionOptions {
  std::string sequence;
  std::string reference;
  std::string query;
  std::string truth;
  std::string out;
  std::string preset = "default";
  std::string keypoints = "orb";
  int max_keypoints = -1;  ///< -1: the preset's
  int min_gap = 10;
  double ratio = -1.0;             ///< -1: the preset's
  double histogram_weight = -1.0;  ///< -1: the preset's
  std::string scoring;             ///< empty: the preset's
  int mutual = -1;                 ///< -1: the preset's, 0 off, 1 on
  int fallback = -1;               ///< -1: the preset's
  double max_angle = -1.0;         ///< -1: the preset's
  int gate = -1;                   ///< -1: the preset's
  bool symmetric = true;
  bool baseline = true;
  bool json = false;
  bool quiet = false;
  double scale = 1.0;  ///< frames are resized by this factor before anything else
  int orb_levels = -1;  ///< -1: the preset's
  int sequence_length = 1;  ///< > 1: each method is also scored as sequences of this many frames
};

/// Strips an optional "images:" scheme: the recognition command reads image files only.
std::string imagePath(const std::string& uri) {
  const std::string scheme = "images:";
  std::string path = uri.rfind(scheme, 0) == 0 ? uri.substr(scheme.size()) : uri;
  if (const auto q = path.find('?'); q != std::string::npos) path = path.substr(0, q);
  return path;
}

struct FrameSet {
  std::vector<std::string> paths;
  std::vector<cv::Mat> images;
};

FrameSet loadFrames(const std::string& uri, const std::string& what, bool quiet, double scale) {
  FrameSet set;
  set.paths = listImageFiles(imagePath(uri));
  Progress progress("recognition", what + " frames", static_cast<std::int64_t>(set.paths.size()), quiet);
  for (std::size_t k = 0; k < set.paths.size(); ++k) {
    progress.update(static_cast<std::int64_t>(k + 1));
    cv::Mat image = readImageFile(set.paths[k]);
    if (scale != 1.0) cv::resize(image, image, cv::Size(), scale, scale, scale > 1.0 ? cv::INTER_CUBIC : cv::INTER_AREA);
    set.images.push_back(image);
  }
  return set;
}

struct MethodResult {
  std::string name;
  std::vector<float> similarity;  // queries x references
  eval::RecognitionScore score;
  double ms_per_comparison = 0.0;
  double ms_per_frame_features = 0.0;
};

// Same-place table of a pairs file: names resolved against the query and reference frame paths.
std::vector<std::uint8_t> sameFromPairs(const eval::Truth& truth, const std::vector<std::string>& queries,
                                        const std::vector<std::string>& references, bool sequence) {
  std::vector<std::uint8_t> same(queries.size() * references.size(), 0);
  int unresolved = 0;
  for (const eval::NamedPair& p : truth.pairs) {
    const int q = eval::resolveFrameName(p.query, queries);
    const int r = eval::resolveFrameName(p.match, references);
    if (q < 0 || r < 0) {
      if (++unresolved <= 3)
        std::cerr << truth.path << ":" << p.line << ": frame '" << (q < 0 ? p.query : p.match)
                  << "' is not among the frames read; pair ignored\n";
      continue;
    }
    same[static_cast<std::size_t>(q) * references.size() + static_cast<std::size_t>(r)] = 1;
    if (sequence) same[static_cast<std::size_t>(r) * references.size() + static_cast<std::size_t>(q)] = 1;
  }
  if (unresolved > 0 && static_cast<std::size_t>(unresolved) == truth.pairs.size())
    throw std::runtime_error(truth.path + ": none of its frame names is among the frames read");
  return same;
}

eval::RecognitionTruth buildTruth(const RecognitionOptions& o, const std::vector<std::string>& queries,
                                  const std::vector<std::string>& references, bool sequence) {
  const eval::Truth truth = eval::loadTruth(o.truth);
  if (truth.kind == eval::Truth::Kind::Matrix) {
    if (!sequence) throw std::invalid_argument(o.truth + ": a loop-closure matrix needs one sequence (SOURCE)");
    if (truth.matrix.size != static_cast<int>(queries.size()))
      throw std::invalid_argument(o.truth + ": the matrix is " + std::to_string(truth.matrix.size) + " x " +
                                  std::to_string(truth.matrix.size) + ", the sequence has " +
                                  std::to_string(queries.size()) + " frames");
    return eval::sequenceTruthFromMatrix(truth.matrix, o.min_gap);
  }
  if (truth.kind == eval::Truth::Kind::Labels) {
    if (!sequence) throw std::invalid_argument(o.truth + ": labels need one sequence (SOURCE)");
    if (truth.labels.size() != queries.size())
      throw std::invalid_argument(o.truth + ": " + std::to_string(truth.labels.size()) + " labelled frames, the sequence has " +
                                  std::to_string(queries.size()));
    std::vector<int> rooms;
    for (const auto& l : truth.labels) rooms.push_back(l.room);
    return eval::sequenceTruthFromRooms(rooms, o.min_gap);
  }
  const std::vector<std::uint8_t> same = sameFromPairs(truth, queries, references, sequence);
  if (!sequence) return eval::crossTruth(static_cast<int>(queries.size()), static_cast<int>(references.size()), same);
  eval::LoopClosureMatrix matrix;
  matrix.size = static_cast<int>(queries.size());
  matrix.same = same;
  return eval::sequenceTruthFromMatrix(matrix, o.min_gap);
}

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// Fills every candidate cell of result.similarity with score(reference r, query q); others stay 0.
template <typename Score>
void fillMatrix(const eval::RecognitionTruth& truth, MethodResult& result, Score score) {
  result.similarity.assign(truth.state.size(), 0.f);
  std::int64_t comparisons = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int q = 0; q < truth.queries; ++q) {
    for (int r = 0; r < truth.references; ++r) {
      if (truth.at(q, r) < 0) continue;
      result.similarity[static_cast<std::size_t>(q) * static_cast<std::size_t>(truth.references) +
                        static_cast<std::size_t>(r)] = static_cast<float>(score(r, q));
      ++comparisons;
    }
  }
  result.ms_per_comparison = comparisons > 0 ? msSince(start) / static_cast<double>(comparisons) : 0.0;
  result.score = eval::scoreRecognition(result.similarity, truth);
}

void writeMatrixCsv(const std::string& path, const MethodResult& m, const eval::RecognitionTruth& truth) {
  OutputFile out(path);
  out << "query,reference,similarity,truth\n";
  for (int q = 0; q < truth.queries; ++q)
    for (int r = 0; r < truth.references; ++r) {
      const std::int8_t s = truth.at(q, r);
      if (s < 0) continue;
      out << q << "," << r << "," << std::setprecision(6)
          << m.similarity[static_cast<std::size_t>(q) * static_cast<std::size_t>(truth.references) + static_cast<std::size_t>(r)]
          << "," << static_cast<int>(s) << "\n";
    }
  out.commit();
}

// Heat map: similarity scaled to the largest candidate value, non-candidates black, true matches framed
// in white (at >= 4 pixels per cell).
void writeHeatMap(const std::string& path, const MethodResult& m, const eval::RecognitionTruth& truth) {
  const int cell = std::max(1, 512 / std::max(truth.queries, truth.references));
  float top = 1e-6f;
  for (float v : m.similarity) top = std::max(top, v);
  cv::Mat grey(truth.queries, truth.references, CV_8UC1, cv::Scalar(0));
  for (int q = 0; q < truth.queries; ++q)
    for (int r = 0; r < truth.references; ++r)
      if (truth.at(q, r) >= 0)
        grey.at<std::uint8_t>(q, r) = cv::saturate_cast<std::uint8_t>(
            255.0f * m.similarity[static_cast<std::size_t>(q) * static_cast<std::size_t>(truth.references) + static_cast<std::size_t>(r)] / top);
  cv::Mat colour;
  cv::applyColorMap(grey, colour, cv::COLORMAP_VIRIDIS);
  for (int q = 0; q < truth.queries; ++q)
    for (int r = 0; r < truth.references; ++r)
      if (truth.at(q, r) < 0) colour.at<cv::Vec3b>(q, r) = cv::Vec3b(0, 0, 0);
  cv::Mat big;
  cv::resize(colour, big, cv::Size(truth.references * cell, truth.queries * cell), 0, 0, cv::INTER_NEAREST);
  if (cell >= 4)
    for (int q = 0; q < truth.queries; ++q)
      for (int r = 0; r < truth.references; ++r)
        if (truth.at(q, r) == 1)
          cv::rectangle(big, cv::Rect(r * cell, q * cell, cell, cell), cv::Scalar(255, 255, 255), 1);
  writeImageFile(path, big);  // temporary name, checked, renamed
}

void writePrSvg(const std::string& path, const std::vector<MethodResult>& methods) {
  const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e"};
  std::vector<eval::PrSeries> curves;
  for (std::size_t k = 0; k < methods.size(); ++k) curves.push_back({methods[k].name, methods[k].score.curve, colours[k % 4]});
  writeFileAtomically(path, renderSvgLinePlot(eval::precisionRecallPlot(
                                "Place recognition: precision-recall of each query's best match", curves)));
}

std::string fixed3(double v) {
  if (std::isnan(v)) return "n/a";
  std::ostringstream s;
  s << std::fixed << std::setprecision(3) << v;
  return s.str();
}

NgramSimilarityConfig similarityConfig(const RecognitionOptions& o, const SimilarityPreset& preset) {
  NgramSimilarityConfig c = preset.similarity;
  if (o.ratio > 0) c.matcher.ratio_test = o.ratio;
  if (o.histogram_weight >= 0) c.histogram_weight = o.histogram_weight;
  if (!o.scoring.empty()) c.keypoint_scoring = parseKeypointScoring(o.scoring);
  if (o.mutual >= 0) c.matcher.mutual_check = o.mutual == 1;
  if (o.fallback >= 0) c.histogram_only_fallback = o.fallback == 1;
  if (o.max_angle >= 0) c.matcher.max_angle_difference_deg = o.max_angle;
  if (o.gate >= 0) c.histogram_gate = o.gate == 1;
  return c;
}

void runRecognition(const RecognitionOptions& o) {
  const bool sequence = !o.sequence.empty();
  if (sequence == (!o.reference.empty() || !o.query.empty()))
    throw std::invalid_argument("give either SOURCE (one sequence) or both --reference and --query");
  if (!sequence && (o.reference.empty() || o.query.empty()))
    throw std::invalid_argument("--reference and --query go together");
  if (o.min_gap < 1) throw std::invalid_argument("--min-gap: must be >= 1");

  const SimilarityPreset preset = similarityPreset(o.preset);
  VpackConfig vpack = preset.fingerprint;
  vpack.keypoints.backend = parseKeypointBackend(o.keypoints);
  if (o.max_keypoints >= 0) vpack.keypoints.setMaxKeypoints(o.max_keypoints);
  if (o.orb_levels > 0) vpack.keypoints.orb_levels = o.orb_levels;
  const VpackExtractor extractor(vpack);
  const NgramSimilarity similarity(similarityConfig(o, preset));

  FrameSet queries = loadFrames(sequence ? o.sequence : o.query, sequence ? "sequence" : "query", o.quiet, o.scale);
  FrameSet references_storage;
  if (!sequence) references_storage = loadFrames(o.reference, "reference", o.quiet, o.scale);
  const FrameSet& references = sequence ? queries : references_storage;
  const eval::RecognitionTruth truth = buildTruth(o, queries.paths, references.paths, sequence);

  // Ours.
  MethodResult ours;
  ours.name = "toposlam (" + o.preset + ", " + std::to_string(vpack.keypoints.max_keypoints) + " " +
              toString(vpack.keypoints.backend) + ")";
  {
    const auto start = std::chrono::steady_clock::now();
    std::vector<Fingerprint> qf;
    for (std::size_t k = 0; k < queries.images.size(); ++k)
      qf.push_back(fingerprintImage(extractor, queries.images[k], queries.paths[k]));
    std::vector<Fingerprint> rf_storage;
    if (!sequence)
      for (std::size_t k = 0; k < references.images.size(); ++k)
        rf_storage.push_back(fingerprintImage(extractor, references.images[k], references.paths[k]));
    const std::vector<Fingerprint>& rf = sequence ? qf : rf_storage;
    ours.ms_per_frame_features = msSince(start) / static_cast<double>(qf.size() + rf_storage.size());
    fillMatrix(truth, ours, [&](int r, int q) {
      return o.symmetric ? similarity.symmetricSimilarity(rf[static_cast<std::size_t>(r)], qf[static_cast<std::size_t>(q)])
                         : similarity.similarity(rf[static_cast<std::size_t>(r)], qf[static_cast<std::size_t>(q)]);
    });
  }
  std::vector<MethodResult> methods{ours};
  if (o.baseline) {
    eval::OrbBaselineConfig bc;
    bc.keypoints = std::max(1, vpack.keypoints.max_keypoints);
    const eval::OrbBaseline baseline(bc);
    MethodResult b;
    b.name = "ORB baseline (" + std::to_string(bc.keypoints) + ", ratio 0.8 + mutual)";
    const auto start = std::chrono::steady_clock::now();
    std::vector<cv::Mat> qd, rd_storage;
    for (const cv::Mat& image : queries.images) qd.push_back(baseline.extract(image));
    if (!sequence)
      for (const cv::Mat& image : references.images) rd_storage.push_back(baseline.extract(image));
    const std::vector<cv::Mat>& rd = sequence ? qd : rd_storage;
    b.ms_per_frame_features = msSince(start) / static_cast<double>(qd.size() + rd_storage.size());
    fillMatrix(truth, b, [&](int r, int q) {
      return baseline.similarity(rd[static_cast<std::size_t>(r)], qd[static_cast<std::size_t>(q)]);
    });
    methods.push_back(std::move(b));
  }
  if (o.sequence_length > 1) {
    // Every method once more, scored as sequences (sequence_similarity.hpp), in the same run.
    std::vector<std::uint8_t> candidate(truth.state.size());
    for (std::size_t k = 0; k < candidate.size(); ++k) candidate[k] = truth.state[k] >= 0 ? 1 : 0;
    const std::size_t singles = methods.size();
    for (std::size_t k = 0; k < singles; ++k) {
      MethodResult m = methods[k];
      m.name += ", seq " + std::to_string(o.sequence_length);
      m.similarity = sequenceSimilarity(methods[k].similarity, candidate, truth.queries, truth.references,
                                        o.sequence_length);
      m.score = eval::scoreRecognition(m.similarity, truth);
      methods.push_back(std::move(m));
    }
  }

  if (!o.out.empty()) {
    fs::create_directories(o.out);
    const std::size_t singles = o.sequence_length > 1 ? methods.size() / 2 : methods.size();
    for (std::size_t k = 0; k < methods.size(); ++k) {
      const std::string suffix = std::string(k % singles == 0 ? "" : "-baseline") + (k >= singles ? "-sequence" : "");
      writeMatrixCsv(o.out + "/similarity" + suffix + ".csv", methods[k], truth);
      writeHeatMap(o.out + "/heatmap" + suffix + ".png", methods[k], truth);
    }
    writePrSvg(o.out + "/precision-recall.svg", methods);
  }

  const auto writeJson = [&](std::ostream& stream) {
    JsonWriter json(stream);
    json.beginObject().field("layout", sequence ? "sequence" : "query-reference").field("truth", o.truth);
    json.field("queries", truth.queries).field("references", truth.references);
    if (sequence) json.field("min_gap", o.min_gap);
    json.field("sequence_length", o.sequence_length);
    json.key("methods").beginArray();
    for (const MethodResult& m : methods) {
      const auto& s = m.score;
      json.beginObject().field("name", m.name).field("auc", s.auc).field("top1", s.top1);
      json.field("recall_at_full_precision", s.recall_at_full_precision);
      json.field("threshold_at_full_precision", s.threshold_at_full_precision);
      json.field("average_precision", s.average_precision).field("queries", s.queries);
      json.field("queries_with_match", s.queries_with_match).field("top1_correct", s.top1_correct);
      json.field("positive_pairs", s.positive_pairs).field("negative_pairs", s.negative_pairs);
      json.field("ms_per_frame_features", m.ms_per_frame_features).field("ms_per_comparison", m.ms_per_comparison);
      json.endObject();
    }
    json.endArray().endObject();
    stream << "\n";
  };
  if (!o.out.empty()) {
    OutputFile out(o.out + "/recognition.json");
    writeJson(out);
    out.commit();
  }
  if (o.json) {
    writeJson(std::cout);
    return;
  }
  std::cout << "place recognition: " << truth.queries << " queries x " << truth.references << " references ("
            << (sequence ? "one sequence, candidates at least " + std::to_string(o.min_gap) + " frames back"
                         : "query set against reference set")
            << "), truth " << o.truth << "\n";
  std::cout << "  queries with a true match: " << methods[0].score.queries_with_match << " of "
            << methods[0].score.queries << "; pairs: " << methods[0].score.positive_pairs << " same place, "
            << methods[0].score.negative_pairs << " different\n\n";
  if (o.sequence_length > 1)
    std::cout << "  \", seq " << o.sequence_length << "\": scored as sequences of " << o.sequence_length
              << " frames (the mean similarity along the diagonal ending at each pair)\n\n";
  std::cout << "  " << std::left << std::setw(48) << "method" << std::right << std::setw(7) << "AUC" << std::setw(8)
            << "top-1" << std::setw(14) << "recall@100%P" << std::setw(12) << "ms/frame" << std::setw(12)
            << "us/compare" << "\n";
  for (const MethodResult& m : methods) {
    std::cout << "  " << std::left << std::setw(48) << m.name << std::right << std::setw(7) << fixed3(m.score.auc)
              << std::setw(8) << fixed3(m.score.top1) << std::setw(14) << fixed3(m.score.recall_at_full_precision)
              << std::setw(12) << fixed3(m.ms_per_frame_features) << std::setw(12)
              << fixed3(1000.0 * m.ms_per_comparison) << "\n";
  }
  if (!o.out.empty())
    std::cout << "\nwrote " << o.out << "/similarity*.csv, heatmap*.png, precision-recall.svg, recognition.json\n";
}

}  // namespace

void addRecognitionCommand(CLI::App& app) {
  auto o = std::make_shared<RecognitionOptions>();
  auto* cmd = app.add_subcommand(
      "recognition",
      "Place recognition on its own against ground truth (AUC, top-1, recall at 100% precision), beside a plain "
      "ORB baseline");
  cmd->add_option("source", o->sequence, "One sequence (images:PATH_OR_GLOB or a folder): each frame against its past");
  cmd->add_option("--reference", o->reference, "Reference set (images:PATH_OR_GLOB or a folder)");
  cmd->add_option("--query", o->query, "Query set, each frame against every reference");
  cmd->add_option("--truth", o->truth,
                  "Ground truth: samples_GT.bmp-style matrix, a pairs CSV (samples_GT_pairs.csv, gt.csv) or labels.csv")
      ->required();
  cmd->add_option("--min-gap", o->min_gap, "One sequence: candidates are at least this many frames back")
      ->capture_default_str();
  cmd->add_option("--preset", o->preset, "Method preset: default (measured on real frames) or thesis")
      ->capture_default_str();
  addKeypointBackendOption(*cmd, o->keypoints);
  cmd->add_option("--max-keypoints", o->max_keypoints, "Keypoints per frame (default: the preset's)");
  cmd->add_option("--ratio", o->ratio, "Override: Lowe ratio of the keypoint matcher");
  cmd->add_option("--histogram-weight", o->histogram_weight, "Override: weight of the histogram part");
  cmd->add_option("--scoring", o->scoring, "Override: keypoint scoring, possible-ngrams or verified-matches");
  cmd->add_option("--mutual", o->mutual, "Override: mutual check, 0 or 1");
  cmd->add_option("--histogram-fallback", o->fallback, "Override: histogram-only fallback, 0 or 1");
  cmd->add_option("--orb-levels", o->orb_levels, "Override: ORB pyramid levels");
  cmd->add_option("--histogram-gate", o->gate, "Override: histograms as a gate (1) or a weighted part (0)");
  cmd->add_option("--max-angle", o->max_angle, "Override: orientation check in degrees (0 = off)");
  cmd->add_flag("!--one-way", o->symmetric, "Score reference -> query only (default: mean of both directions)");
  cmd->add_flag("!--no-baseline", o->baseline, "Skip the ORB baseline");
  cmd->add_option("--out", o->out, "Folder for matrices (CSV), heat maps (PNG), precision-recall (SVG), JSON");
  cmd->add_flag("--json", o->json, "Print JSON instead of the table");
  cmd->add_flag("--quiet", o->quiet, "No progress on stderr");
  cmd->add_option("--sequence", o->sequence_length,
                  "Also score every method as sequences of this many frames (SeqSLAM-style; 1: single frames only)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--scale", o->scale, "Resize every frame by this factor first (both methods)")
      ->check(CLI::Range(0.05, 8.0));
  cmd->callback([o] { runRecognition(*o); });
}

}  // namespace toposlam::cli
