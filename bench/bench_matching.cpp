// `toposlam-bench similarity`: n-gram similarities per second on one core (issue target: >= 20,000/s for
// 640x480 ORB fingerprints). Fingerprints the sample frames once (upscaled to --size), then times every
// NgramSimilarity call of --repeat passes over all ordered pairs of --frames frames. Prints the median and
// p99 time per similarity and the rate per pass; asserts nothing.
#include <algorithm>
#include <iomanip>
#include <iostream>
#include <memory>

#include <opencv2/core/utility.hpp>

#include "bench_stats.hpp"
#include "benchmarks.hpp"
#include "image_input.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/matching/similarity_preset.hpp"

namespace toposlam::cli {

namespace {

struct MatchingBenchOptions {
  std::string samples;
  int repeat = 5;
  int frames = 40;
  int width = 640;
  int height = 480;
  std::vector<std::string> backends = {"orb"};
  std::vector<std::string> presets = {"default", "thesis"};
  std::vector<int> budgets;  ///< keypoints per frame to measure; empty: the preset's
  bool json = false;
};

void runMatchingBench(const MatchingBenchOptions& o) {
  cv::setNumThreads(1);  // one core: the matcher is single-threaded, keep OpenCV from spreading extraction
  BenchRows rows("similarity", o.json);
  const cv::Size size(o.width, o.height);
  std::vector<cv::Mat> frames = loadSampleFrames(o.samples, size);
  if (static_cast<int>(frames.size()) > o.frames) frames.resize(static_cast<std::size_t>(o.frames));
  rows.text() << "n-gram similarity, one thread, " << frames.size() << " frames at " << size.width << "x"
            << size.height << ", all ordered pairs x " << o.repeat << " passes (" << o.samples << ")\n";
  rows.text() << std::left << std::setw(16) << "preset kp" << std::right << std::setw(10) << "pairs" << std::setw(14)
            << "keypoints/f" << std::setw(13) << "letters/f" << std::setw(13) << "median us" << std::setw(10)
            << "p99 us" << std::setw(16) << "median sim/s" << std::setw(14) << "worst sim/s" << "\n";
  const std::vector<int> budgets = o.budgets.empty() ? std::vector<int>{-1} : o.budgets;
  for (const std::string& preset_name : o.presets)
  for (const int budget : budgets)
  for (const std::string& backend : o.backends) {
    const SimilarityPreset preset = similarityPreset(preset_name);
    VpackConfig config = preset.fingerprint;
    config.keypoints.backend = parseKeypointBackend(backend);
    if (budget > 0) config.keypoints.setMaxKeypoints(budget);
    const VpackExtractor extractor(config);
    std::vector<Fingerprint> prints;
    double keypoints = 0, letters = 0;
    for (const cv::Mat& frame : frames) {
      prints.push_back(extractor.extract(frame));
      keypoints += prints.back().keypointCount();
      letters += static_cast<double>(prints.back().subregions.size());
    }
    const NgramSimilarity similarity(preset.similarity);
    MatchScratch scratch;
    std::vector<double> call_ms;     // one entry per similarity
    std::vector<double> pass_rates;  // similarities per second, one entry per pass
    double checksum = 0;             // keeps the calls from being optimised away
    std::size_t pairs = 0;
    for (int pass = 0; pass < o.repeat; ++pass) {
      Stopwatch pass_watch;
      std::size_t pass_pairs = 0;
      for (const Fingerprint& reference : prints) {
        for (const Fingerprint& query : prints) {
          Stopwatch watch;
          checksum += similarity.similarity(reference, query, scratch);
          call_ms.push_back(watch.elapsedMs());
          ++pass_pairs;
        }
      }
      pass_rates.push_back(static_cast<double>(pass_pairs) / (pass_watch.elapsedMs() / 1000.0));
      pairs += pass_pairs;
    }
    const TimingSummary s = summarize(call_ms);
    std::sort(pass_rates.begin(), pass_rates.end());
    const std::size_t n = prints.size();
    rows.row({{"preset", preset_name}, {"keypoints_backend", backend}, {"pairs", static_cast<std::int64_t>(pairs)},
              {"keypoints_per_frame", keypoints / static_cast<double>(n)}, {"letters_per_frame", letters / static_cast<double>(n)},
              {"median_us", 1000.0 * s.median_ms}, {"p99_us", 1000.0 * s.p99_ms},
              {"median_similarities_per_s", pass_rates[pass_rates.size() / 2]},
              {"worst_similarities_per_s", pass_rates.front()}, {"mean_similarity", checksum / static_cast<double>(pairs)}});
    rows.text() << std::left << std::setw(16) << (preset_name + " " + backend) << std::right << std::setw(10) << pairs << std::fixed
              << std::setprecision(1) << std::setw(14) << keypoints / static_cast<double>(n) << std::setw(13)
              << letters / static_cast<double>(n) << std::setw(13) << 1000.0 * s.median_ms << std::setw(10)
              << 1000.0 * s.p99_ms << std::setprecision(0) << std::setw(16) << pass_rates[pass_rates.size() / 2]
              << std::setw(14) << pass_rates.front() << "\n";
    rows.text() << "  (mean similarity " << std::setprecision(4) << checksum / static_cast<double>(pairs) << ")\n";
  }
}

}  // namespace

void addBenchMatching(CLI::App& bench) {
  auto options = std::make_shared<MatchingBenchOptions>();
  options->samples = defaultSamplesFolder();
  auto* cmd = bench.add_subcommand("similarity", "n-gram similarities per second on one core (640x480 ORB)");
  cmd->add_option("--samples", options->samples, "Folder of frames")->capture_default_str();
  cmd->add_option("--repeat", options->repeat, "Passes over all pairs")->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--frames", options->frames, "Frames used (pairs = frames^2 per pass)")
      ->check(CLI::Range(2, 10000))->capture_default_str();
  cmd->add_option("--width", options->width, "Frame width after resizing")->check(CLI::Range(64, 4096))
      ->capture_default_str();
  cmd->add_option("--height", options->height, "Frame height after resizing")->check(CLI::Range(48, 4096))
      ->capture_default_str();
  cmd->add_option("--preset", options->presets, "Presets to measure (default, thesis)")->capture_default_str();
  cmd->add_option("--keypoints", options->backends, "Backends to measure (orb, sift, brisk, akaze)")
      ->capture_default_str();
  cmd->add_option("--max-keypoints", options->budgets, "Keypoint budgets per frame to measure (default: the preset's)")
      ->check(CLI::Range(1, 5000));
  cmd->add_flag("--json", options->json, "Print the rows as one JSON object (the table goes to stderr)");
  cmd->callback([options] { runMatchingBench(*options); });
}

}  // namespace toposlam::cli
