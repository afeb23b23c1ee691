// `toposlam-bench topology`: ms per TopologyParticleFilter step (500 particles) at 10, 100 and 1000
// places with synthetic fingerprints and a cheap fake similarity, the longest slice of a step run with
// advance(budget), and, separately, what the once-per-step similarity against N real stored
// representatives costs with NgramSimilarity (VPACK of the bundled sample frames). Prints, fails nothing.
#include <cstdint>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>
#include <span>
#include <vector>

#include <opencv2/core/utility.hpp>

#include "bench_stats.hpp"
#include "benchmarks.hpp"
#include "config_key_options.hpp"
#include "image_input.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam::cli {

namespace {

struct TopologyBenchOptions {
  std::vector<int> places = {10, 100, 1000};
  int particles = keyDefaultInt("topology.particles");
  int steps = 100;   ///< measured steps (a second traversal) per map size
  int budget = 250;  ///< work items per slice for the sliced measurement
  /// Other frames per new place (segmentation.place_samples); > 0 steps with the relative likelihood.
  int place_samples = keyDefaultInt("segmentation.place_samples");
  std::string samples;
  bool real = true;
  bool json = false;
};

/// Synthetic fingerprint: only its tag (image width - 1) matters to the fake similarity.
std::shared_ptr<const Fingerprint> tagged(int tag) {
  auto f = std::make_shared<Fingerprint>();
  f->image_width = tag + 1;
  f->image_height = 1;
  Subregion whole;
  whole.column_end = tag + 1;
  f->subregions.push_back(whole);
  return f;
}

/// Same tag: 0.8; otherwise a fixed pseudo-random value in [0, 0.08) (distinctive places).
class FakeSimilarity : public SimilarityMeasure {
 public:
  double similarity(const Fingerprint& reference, const Fingerprint& query) const override {
    const auto a = static_cast<std::uint64_t>(reference.image_width);
    const auto b = static_cast<std::uint64_t>(query.image_width);
    if (a == b) return 0.8;
    std::uint64_t h = (a * 0x9E3779B97F4A7C15ULL) ^ (b + 0x632BE59BD9B4E019ULL);
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ULL;
    h ^= h >> 32;
    return 0.08 * static_cast<double>(h % 1000) / 1000.0;
  }
};

void runFilterBench(const TopologyBenchOptions& o, BenchRows& rows) {
  rows.text() << "TopologyParticleFilter, " << o.particles << " particles, fake similarity; a first traversal "
            << "builds N places, then " << o.steps << " steps of a second traversal are measured; "
            << (o.place_samples > 0 ? "relative likelihood, " + std::to_string(o.place_samples) + " place samples"
                                    : std::string("the representative alone"))
            << "\n";
  rows.text() << std::setw(8) << "places" << std::setw(12) << "median ms" << std::setw(10) << "p99 ms"
            << std::setw(10) << "max ms" << std::setw(14) << "slice max ms" << std::setw(10) << "states"
            << std::setw(10) << "records" << std::setw(8) << "best p"
            << "\n";
  FakeSimilarity similarity;
  for (int places : o.places) {
    TopologyFilterConfig config;
    config.particles = o.particles;
    config.seed = 1;
    if (o.place_samples > 0) config.likelihood = LikelihoodModel::Relative;
    TopologyParticleFilter filter(config, similarity);
    std::vector<std::shared_ptr<const Fingerprint>> place_samples;
    auto samplesOf = [&](int tag) {
      place_samples.assign(static_cast<std::size_t>(o.place_samples), tagged(tag));
      return std::span<const std::shared_ptr<const Fingerprint>>(place_samples);
    };
    for (int p = 0; p < places; ++p) filter.step(tagged(p), {}, samplesOf(p));
    std::vector<double> step_ms, slice_ms;
    for (int k = 0; k < o.steps; ++k) {
      auto fingerprint = tagged(k % places);
      const std::span<const std::shared_ptr<const Fingerprint>> samples = samplesOf(k % places);
      if (k % 2 == 0) {
        Stopwatch watch;
        filter.step(fingerprint, {}, samples);
        step_ms.push_back(watch.elapsedMs());
      } else {
        // Sliced: the pipeline's way of spreading a step over frames.
        filter.beginStep(fingerprint, {}, samples);
        bool done = false;
        while (!done) {
          Stopwatch watch;
          done = filter.advance(static_cast<std::size_t>(o.budget));
          slice_ms.push_back(watch.elapsedMs());
        }
      }
    }
    const TimingSummary s = summarize(step_ms);
    const TimingSummary sl = summarize(slice_ms);
    const TopologyMemoryStats memory = filter.memoryStats();
    rows.row({{"part", std::string("filter step")}, {"places", std::int64_t{places}}, {"median_ms", s.median_ms},
              {"p99_ms", s.p99_ms}, {"max_ms", s.max_ms}, {"slice_max_ms", sl.max_ms},
              {"states", static_cast<std::int64_t>(memory.distinct_states)},
              {"records", static_cast<std::int64_t>(memory.history_records)},
              {"best_probability", filter.estimate(0).best.probability}});
    rows.text() << std::setw(8) << places << std::fixed << std::setprecision(3) << std::setw(12) << s.median_ms
              << std::setw(10) << s.p99_ms << std::setw(10) << s.max_ms << std::setw(14) << sl.max_ms
              << std::setw(10) << memory.distinct_states << std::setw(10) << memory.history_records
              << std::setw(8) << std::setprecision(2) << filter.estimate(0).best.probability << "\n";
  }
}

void runRealSimilarityBench(const TopologyBenchOptions& o, BenchRows& rows) {
  cv::setNumThreads(1);
  const std::vector<cv::Mat> frames = loadSampleFrames(o.samples, cv::Size(320, 240));
  if (frames.size() < 2) {
    rows.text() << "real similarity: fewer than 2 frames in " << o.samples << ", skipped\n";
    return;
  }
  VpackExtractor extractor;
  std::vector<Fingerprint> fingerprints;
  for (const cv::Mat& frame : frames) fingerprints.push_back(extractor.extract(frame));
  NgramSimilarity similarity;
  rows.text() << "\nOnce-per-step similarity of one new representative against N stored ones (NgramSimilarity, "
            << "VPACK ORB at 320x240 of " << fingerprints.size() << " frames of " << o.samples
            << ", 1 thread)\n";
  rows.text() << std::setw(8) << "places" << std::setw(12) << "median ms" << std::setw(10) << "p99 ms"
            << std::setw(14) << "us per pair"
            << "\n";
  for (int places : o.places) {
    std::vector<double> ms;
    const int repeats = places >= 1000 ? 5 : (places >= 100 ? 20 : 100);
    double sink = 0.0;
    for (int r = 0; r < repeats; ++r) {
      const Fingerprint& query = fingerprints[static_cast<std::size_t>(r) % fingerprints.size()];
      Stopwatch watch;
      for (int i = 0; i < places; ++i) {
        sink += similarity.similarity(fingerprints[static_cast<std::size_t>(i + r + 1) % fingerprints.size()],
                                      query);
      }
      ms.push_back(watch.elapsedMs());
    }
    const TimingSummary s = summarize(ms);
    rows.row({{"part", std::string("real similarity")}, {"places", std::int64_t{places}}, {"median_ms", s.median_ms},
              {"p99_ms", s.p99_ms}, {"us_per_pair", 1000.0 * s.median_ms / places}});
    rows.text() << std::setw(8) << places << std::fixed << std::setprecision(3) << std::setw(12) << s.median_ms
              << std::setw(10) << s.p99_ms << std::setw(14) << std::setprecision(1)
              << 1000.0 * s.median_ms / places << (sink < 0 ? " " : "") << "\n";
  }
}

}  // namespace

void addBenchTopology(CLI::App& bench) {
  auto options = std::make_shared<TopologyBenchOptions>();
  options->samples = defaultSamplesFolder();
  auto* cmd = bench.add_subcommand("topology", "ms per particle-filter step at 10, 100, 1000 places");
  cmd->add_option("--places", options->places, "Map sizes to measure")->capture_default_str();
  cmd->add_option("--particles", options->particles, "Particles")
      ->check(keyRange("topology.particles"))
      ->capture_default_str();
  cmd->add_option("--steps", options->steps, "Measured steps per map size")
      ->check(CLI::Range(2, 100000))
      ->capture_default_str();
  cmd->add_option("--budget", options->budget, "Work items per slice (sliced steps)")
      ->check(CLI::Range(1, 100000000))
      ->capture_default_str();
  cmd->add_option("--place-samples", options->place_samples,
                  "Other frames per new place in the filter part (0 = the representative alone)")
      ->check(keyRange("segmentation.place_samples"))
      ->capture_default_str();
  cmd->add_option("--samples", options->samples, "Frames for the real-similarity part")
      ->capture_default_str();
  cmd->add_flag("!--no-real", options->real, "Skip the real-similarity part");
  cmd->add_flag("--json", options->json, "Print the rows as one JSON object (the table goes to stderr)");
  cmd->callback([options] {
    BenchRows rows("topology", options->json);
    runFilterBench(*options, rows);
    if (options->real) runRealSimilarityBench(*options, rows);
  });
}

}  // namespace toposlam::cli
