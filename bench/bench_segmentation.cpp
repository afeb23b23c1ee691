// `toposlam-bench segmentation`: ms per frame of the segmentation step (FiedlerSegmenter::addFrame:
// the new frame's 2 (n-1) n-gram similarities, L_sym, lambda2, valley detection, representatives) on
// ORB fingerprints of the sample frames upscaled to 640x480. Reported twice: with the real similarity,
// and with the similarities looked up from a precomputed table (the linear algebra alone; the thesis
// quotes 1.4 ms for that part and 140-198 ms in all). Only frames with a full window count.
#include <algorithm>
#include <iomanip>
#include <iostream>
#include <memory>
#include <unordered_map>

#include <opencv2/core/utility.hpp>

#include "bench_stats.hpp"
#include "benchmarks.hpp"
#include "image_input.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"

namespace toposlam::cli {

namespace {

struct SegmentationBenchOptions {
  std::string samples;
  int repeat = 10;
  std::vector<int> windows = {25};
  std::string keypoints = "orb";
  bool json = false;
};

/// Similarities read from a table computed beforehand (isolates the segmenter's own cost).
class PrecomputedSimilarity : public SimilarityMeasure {
 public:
  PrecomputedSimilarity(const std::vector<std::shared_ptr<const Fingerprint>>& prints,
                        const SimilarityMeasure& real)
      : size_(prints.size()), table_(size_ * size_) {
    for (std::size_t i = 0; i < size_; ++i) index_[prints[i].get()] = i;
    for (std::size_t i = 0; i < size_; ++i)
      for (std::size_t j = 0; j < size_; ++j) table_[i * size_ + j] = real.similarity(*prints[i], *prints[j]);
  }
  double similarity(const Fingerprint& reference, const Fingerprint& query) const override {
    return table_[index_.at(&reference) * size_ + index_.at(&query)];
  }

 private:
  std::size_t size_;
  std::vector<double> table_;
  std::unordered_map<const Fingerprint*, std::size_t> index_;
};

TimingSummary timeSegmenter(const std::vector<std::shared_ptr<const Fingerprint>>& prints,
                            const SimilarityMeasure& similarity, int window, int repeat,
                            std::size_t& places) {
  FiedlerSegmenterConfig config;
  config.window = window;
  config.valley.gamma = std::min(config.valley.gamma, maxFiedlerValue(window));
  config.valley.delta = std::min(config.valley.delta, config.valley.gamma);
  FiedlerSegmenter segmenter(config, similarity);
  std::vector<double> ms;
  std::int64_t frame = 0;
  places = 0;
  for (int pass = 0; pass < repeat; ++pass) {
    for (const auto& print : prints) {
      Stopwatch watch;
      const SegmenterStep step = segmenter.addFrame(frame, 0.2 * static_cast<double>(frame), print);
      const double elapsed = watch.elapsedMs();
      if (frame >= window - 1) ms.push_back(elapsed);
      if (step.closed_place) ++places;
      ++frame;
    }
  }
  if (segmenter.flush()) ++places;
  return summarize(ms);
}

void runSegmentationBench(const SegmentationBenchOptions& o) {
  cv::setNumThreads(1);  // one core, as the target says
  VpackConfig vpack;
  vpack.keypoints.backend = parseKeypointBackend(o.keypoints);
  const VpackExtractor extractor(vpack);
  std::vector<std::shared_ptr<const Fingerprint>> prints;
  for (const cv::Mat& frame : loadSampleFrames(o.samples, cv::Size(640, 480))) {
    prints.push_back(std::make_shared<const Fingerprint>(extractor.extract(frame)));
  }
  double keypoints = 0;
  for (const auto& p : prints) keypoints += p->keypointCount();
  const NgramSimilarity similarity;
  const PrecomputedSimilarity table(prints, similarity);
  BenchRows rows("segmentation", o.json);
  rows.text() << "Segmentation step per frame (FiedlerSegmenter::addFrame), " << prints.size()
            << " fingerprints x " << o.repeat << " passes, 640x480 " << o.keypoints << " (" << std::fixed
            << std::setprecision(1) << keypoints / static_cast<double>(prints.size())
            << " keypoints/frame), one thread, full windows only\n";
  rows.text() << std::left << std::setw(8) << "window" << std::setw(22) << "similarity" << std::right
            << std::setw(12) << "median ms" << std::setw(10) << "p99 ms" << std::setw(10) << "max ms"
            << std::setw(10) << "places"
            << "\n";
  for (int window : o.windows) {
    for (int variant = 0; variant < 2; ++variant) {
      std::size_t places = 0;
      const TimingSummary s =
          timeSegmenter(prints, variant == 0 ? static_cast<const SimilarityMeasure&>(similarity) : table,
                        window, o.repeat, places);
      rows.row({{"window", std::int64_t{window}},
                {"similarity", std::string(variant == 0 ? "n-gram" : "precomputed table")}, {"median_ms", s.median_ms},
                {"p99_ms", s.p99_ms}, {"max_ms", s.max_ms}, {"places", static_cast<std::int64_t>(places)}});
      rows.text() << std::left << std::setw(8) << window << std::setw(22)
                << (variant == 0 ? "n-gram (2(n-1) calls)" : "precomputed table") << std::right << std::fixed
                << std::setprecision(3) << std::setw(12) << s.median_ms << std::setw(10) << s.p99_ms
                << std::setw(10) << s.max_ms << std::setw(10) << places << "\n";
    }
  }
}

}  // namespace

void addBenchSegmentation(CLI::App& bench) {
  auto options = std::make_shared<SegmentationBenchOptions>();
  options->samples = defaultSamplesFolder();
  auto* cmd = bench.add_subcommand("segmentation",
                                   "ms per frame of the segmentation step (window 25, similarities "
                                   "included), 640x480 fingerprints");
  cmd->add_option("--samples", options->samples, "Folder of frames")->capture_default_str();
  cmd->add_option("--repeat", options->repeat, "Passes over the frames")->check(CLI::Range(1, 1000));
  cmd->add_option("--window", options->windows, "Window sizes to measure")->capture_default_str();
  cmd->add_option("--keypoints", options->keypoints, "Keypoint backend")->capture_default_str();
  cmd->add_flag("--json", options->json, "Print the rows as one JSON object (the table goes to stderr)");
  cmd->callback([options] { runSegmentationBench(*options); });
}

}  // namespace toposlam::cli
