// `toposlam-bench map-size`: what a new place costs as the map grows (issue 18: 10,000 places under 20 ms
// and 200 MB resident with 500 particles; issue 38: 100,000 places, < 500 MB), with the candidate index
// (docs/topology.md, "Large maps"), how often its decision equals the exhaustive comparison's, and what
// the map file of the end state costs to save and to load.
//
// The run is synthetic but made of real fingerprints: each place's prototype is one of the bundled
// sample frames' VPACK fingerprints (its edges, subregions and keypoints) with its descriptor bits
// scrambled (each flipped with probability 0.35, so two places never share keypoints yet keep ORB's bit
// statistics) and its colours permuted; an observation of a place flips a few bits of the prototype's
// descriptors (4 %) and replaces a share of its keypoints, as a revisit does. The route mostly meets new
// places and now and then goes back over a stretch of earlier ones (--revisit-share).
//
// Every --compare-every steps the filter is forked (shared state, TopologyParticleFilter::fork) and the
// fork takes the same step exhaustively: the decision (the founding observation of the most probable
// current node over the particles) is compared with the indexed step's, over all compared steps and over
// those where the exhaustive filter has decided (its most probable node has p >= 0.5). Timings are the indexed filter's steps only; RSS is the
// process's (VmRSS) at each checkpoint; "compared" is the mean number of exact similarity evaluations per
// step; "cmp ms" is the median time of a step spent in those evaluations (a timing wrapper around the
// similarity) and "rest ms" the median of the rest of the step (the filter's own work). Prints numbers (and
// an SVG with --svg), fails nothing. "est ms" is one TopologyParticleFilter::estimate(4) at the checkpoint,
// not part of the step (the pipeline calls it after each step).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <time.h>
#include <unistd.h>

#include <opencv2/core/utility.hpp>

#include "bench_stats.hpp"
#include "benchmarks.hpp"
#include "image_input.hpp"
#include "synthetic_places.hpp"
#include "toposlam/config/method_preset.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/core/svg_plot.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/pipeline/map_files.hpp"
#include "toposlam/platform/process_resources.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam::cli {

namespace {

struct MapSizeBenchOptions {
  int places = 10000;  ///< steps (observations)
  int particles = 500;
  int checkpoint = 1000;
  int compare_every = 50;
  double revisit_share = 0.3;
  std::uint64_t seed = 1;
  std::string samples;
  std::string svg;
  bool json = false;
  bool control = false;  ///< also a second exhaustive fork whose similarities differ by 1e-6
  bool map_file = true;  ///< at the end, save the map as toposlamd does and load it again, timed
  CandidateSelectionConfig candidates;
};

/// The control's similarity: the same up to a relative 1e-6 that depends on the pair (deterministic).
class NudgedSimilarity final : public SimilarityMeasure {
 public:
  explicit NudgedSimilarity(const SimilarityMeasure& inner) : inner_(inner) {}
  double similarity(const Fingerprint& reference, const Fingerprint& query) const override {
    const double s = inner_.similarity(reference, query);
    const auto a = reference.descriptors.empty() ? 0u : reference.descriptors.data[0];
    const auto b = query.descriptors.empty() ? 0u : query.descriptors.data[1];
    return s * (1.0 + 1e-6 * (static_cast<double>((a * 31u + b) % 17u) / 16.0 - 0.5));
  }

 private:
  const SimilarityMeasure& inner_;
};

/// The filter's similarity, timed: how much of a step the exact comparisons take (the rest is the
/// filter's own bookkeeping, which must not grow with the map).
class TimedSimilarity final : public SimilarityMeasure {
 public:
  explicit TimedSimilarity(const SimilarityMeasure& inner) : inner_(inner) {}
  double similarity(const Fingerprint& reference, const Fingerprint& query) const override {
    const auto start = std::chrono::steady_clock::now();
    const double s = inner_.similarity(reference, query);
    elapsed_ += std::chrono::steady_clock::now() - start;
    return s;
  }
  /// ms spent in similarity() since the last call.
  double takeMs() const {
    const double ms = std::chrono::duration<double, std::milli>(elapsed_).count();
    elapsed_ = {};
    return ms;
  }

 private:
  const SimilarityMeasure& inner_;
  mutable std::chrono::steady_clock::duration elapsed_{};
};

/// The decision: where the robot is, as the most probable current node over all particles (its founding
/// observation; -1 before the first step). Not the node in the single most probable topology, which
/// near-ties among many similar topologies make flip with any difference in the weights.
int decisionOf(const TopologyParticleFilter& filter) {
  const TopologyEstimate e = filter.estimate(0);
  return e.locations.empty() ? -1 : e.locations.front().founding_observation;
}

struct Checkpoint {
  int steps = 0;
  std::size_t stored = 0;
  TimingSummary step;
  TimingSummary compare;  ///< ms of a step spent in the exact comparisons
  TimingSummary rest;     ///< ms of a step spent elsewhere (the filter's bookkeeping)
  double estimate_ms = 0;  ///< one TopologyParticleFilter::estimate(4) at the checkpoint (what a user reads after a step)
  double rss_mb = 0, index_mb = 0;
  double comparisons = 0;  ///< exact similarity evaluations per step, mean over the window
  int compared = 0, agreed = 0;
  int confident = 0, confident_agreed = 0;  ///< steps where the exhaustive decision has p >= 0.5
};

/// The map file at the end of the run, as toposlamd saves and loads it: the snapshot (TopologyParticleFilter::
/// freeze, in the topology thread: the only part on the frame path), the encoding and the atomic write
/// (MapStore::encode and writeAtomically, in the map writer thread), then a load (MapStore::load: read,
/// checksum, parse, index rebuilt), as a restart does.
struct MapFileTimes {
  double snapshot_ms = 0, encode_ms = 0, write_ms = 0, load_ms = 0;  ///< wall clock
  double encode_cpu_ms = 0, load_cpu_ms = 0;  ///< the process's CPU time (the machine's other work excluded)
  double megabytes = 0;
  int loaded_observations = 0;
};

double processCpuMs() {
  timespec t{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

MapFileTimes timeMapFile(const TopologyParticleFilter& filter, const SimilarityMeasure& similarity) {
  MapFileTimes t;
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("toposlam-bench-map-size-" + std::to_string(::getpid()) + ".tsm");
  {
    Stopwatch snapshot_watch;
    const FrozenTopologyState frozen = filter.freeze();
    t.snapshot_ms = snapshot_watch.elapsedMs();
    Stopwatch encode_watch;
    const double encode_cpu = processCpuMs();
    const std::string bytes = MapStore::encode(frozen);
    t.encode_cpu_ms = processCpuMs() - encode_cpu;
    t.encode_ms = encode_watch.elapsedMs();
    t.megabytes = static_cast<double>(bytes.size()) / (1024.0 * 1024.0);
    Stopwatch write_watch;
    MapStore::writeAtomically(path, bytes);
    t.write_ms = write_watch.elapsedMs();
  }
  Stopwatch load_watch;
  const double load_cpu = processCpuMs();
  const LoadedMap loaded = MapStore::load(path, similarity, std::uint64_t{1} << 40);
  t.load_cpu_ms = processCpuMs() - load_cpu;
  t.load_ms = load_watch.elapsedMs();
  t.loaded_observations = loaded.filter->observationCount();
  std::error_code ec;
  std::filesystem::remove(path, ec);
  std::filesystem::remove(MapStore::previousPath(path), ec);
  return t;
}

/// Where --svg OUT puts the memory plot: OUT with "-memory" before its extension.
std::string memoryPlotPath(const std::string& svg) {
  const std::filesystem::path p(svg);
  return (p.parent_path() / (p.stem().string() + "-memory" + p.extension().string())).string();
}

void runMapSizeBench(const MapSizeBenchOptions& o) {
  cv::setNumThreads(1);
  const MethodPreset preset = methodPreset("default");
  const std::vector<Fingerprint> donors = donorFingerprints(o.samples, preset.fingerprint, "map-size");
  const NgramSimilarity similarity(preset.similarity);
  TopologyFilterConfig config = preset.topology;
  config.particles = o.particles;
  config.seed = o.seed;
  config.candidates = o.candidates;
  const TimedSimilarity timed(similarity);
  TopologyParticleFilter filter(config, timed);
  CandidateSelectionConfig exhaustive = o.candidates;
  exhaustive.exhaustive_up_to = 1000000000;

  std::mt19937_64 rng(o.seed);
  std::vector<int> route;  // place of each step
  int place_count = 0;
  while (static_cast<int>(route.size()) < o.places) {
    const int length = 5 + static_cast<int>(rng() % 11);
    if (place_count > 20 && uniform(rng) < o.revisit_share) {
      const int start = static_cast<int>(rng() % static_cast<std::uint64_t>(place_count - length));
      for (int i = 0; i < length && static_cast<int>(route.size()) < o.places; ++i) route.push_back(start + i);
    } else {
      for (int i = 0; i < length && static_cast<int>(route.size()) < o.places; ++i) route.push_back(place_count++);
    }
  }
  // A place's prototype is made again from its own seed whenever it is met (not kept: only what the
  // filter stores should count in the resident memory).
  const auto prototype = [&](int place) {
    std::mt19937_64 place_rng(o.seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(place));
    return prototypeOf(donors[static_cast<std::size_t>(place) % donors.size()], place_rng);
  };

  std::vector<Checkpoint> checkpoints;
  // The plot: per 1 % of the run, the median and p99 ms of its steps and the resident MB at its end.
  const int plot_every = std::max(1, o.places / 100);
  double window_comparisons = 0;
  std::vector<double> window_ms, window_compare_ms, window_rest_ms, plot_window_ms, plot_window_rest_ms, plot_x,
      plot_median, plot_p99, plot_rest, plot_rss;
  int compared = 0, agreed = 0, window_compared = 0, window_agreed = 0;
  int confident = 0, confident_agreed = 0, window_confident = 0, window_confident_agreed = 0;
  int control_same = 0, control_confident = 0, control_confident_same = 0;
  const NudgedSimilarity nudged(similarity);
  if (!o.json)
    std::printf("map-size: %d steps, %d particles, %zu donor frames of %s; exhaustive up to %d stored, then %d "
                "candidates + %d background samples; decisions compared every %d steps\n%8s %8s %10s %10s %10s "
                "%8s %9s %9s %14s %14s %8s %8s %8s\n",
                o.places, o.particles, donors.size(), o.samples.c_str(), o.candidates.exhaustive_up_to,
                o.candidates.candidates, o.candidates.background_samples, o.compare_every, "steps", "stored",
                "median ms", "p99 ms", "max ms", "RSS MB", "index MB", "compared", "same decision", "when p >= 0.5",
                "cmp ms", "rest ms", "est ms");
  for (int k = 0; k < o.places; ++k) {
    const auto observation = observationOf(prototype(route[static_cast<std::size_t>(k)]), rng);
    std::unique_ptr<TopologyParticleFilter> shadow;
    if (o.compare_every > 0 && k > 0 && k % o.compare_every == 0) {
      shadow = filter.fork();
      shadow->setCandidateSelection(exhaustive);
    }
    timed.takeMs();  // the shadows' comparisons are not the step's
    Stopwatch watch;
    filter.step(observation);
    const double ms = watch.elapsedMs();
    const double compare_ms = timed.takeMs();
    window_ms.push_back(ms);
    window_compare_ms.push_back(compare_ms);
    window_rest_ms.push_back(ms - compare_ms);
    plot_window_rest_ms.push_back(ms - compare_ms);
    window_comparisons += static_cast<double>(filter.lastStepComparisons());
    plot_window_ms.push_back(ms);
    if ((k + 1) % plot_every == 0) {
      const TimingSummary s = summarize(plot_window_ms);
      plot_x.push_back(k + 1);
      plot_median.push_back(s.median_ms);
      plot_p99.push_back(s.p99_ms);
      plot_rest.push_back(summarize(plot_window_rest_ms).median_ms);
      plot_window_rest_ms.clear();
      plot_rss.push_back(static_cast<double>(residentBytes()) / (1024.0 * 1024.0));
      plot_window_ms.clear();
    }
    if (shadow) {
      std::unique_ptr<TopologyParticleFilter> control;
      if (o.control) {
        control = shadow->fork(nudged);  // before the shadow's step: the same state
      }
      shadow->step(observation);
      const bool same = decisionOf(*shadow) == decisionOf(filter);
      if (control) {
        control->step(observation);
        const bool control_agrees = decisionOf(*control) == decisionOf(*shadow);
        control_same += control_agrees;
        const TopologyEstimate e = shadow->estimate(0);
        if (!e.locations.empty() && e.locations.front().probability >= 0.5) {
          ++control_confident;
          control_confident_same += control_agrees;
        }
      }
      if (!same && std::getenv("TOPOSLAM_DEBUG_MAPSIZE")) {
        const TopologyEstimate a = filter.estimate(0), b = shadow->estimate(0);
        std::fprintf(stderr, "step %d place %d: indexed %d (p %.2f) exhaustive %d (p %.2f); first seen %d\n", k,
                     route[static_cast<std::size_t>(k)], a.locations[0].founding_observation, a.locations[0].probability,
                     b.locations[0].founding_observation, b.locations[0].probability,
                     static_cast<int>(std::find(route.begin(), route.end(), route[static_cast<std::size_t>(k)]) - route.begin()));
      }
      ++compared, ++window_compared;
      agreed += same, window_agreed += same;
      const TopologyEstimate exhaustive_estimate = shadow->estimate(0);
      if (!exhaustive_estimate.locations.empty() && exhaustive_estimate.locations.front().probability >= 0.5) {
        ++confident, ++window_confident;
        confident_agreed += same, window_confident_agreed += same;
      }
      shadow.reset();
    }
    if ((k + 1) % o.checkpoint == 0 || k + 1 == o.places) {
      Checkpoint c;
      c.steps = k + 1;
      c.stored = filter.memoryStats().stored_fingerprints;
      c.step = summarize(window_ms);
      {
        Stopwatch estimate_watch;
        const TopologyEstimate e = filter.estimate(4);
        c.estimate_ms = estimate_watch.elapsedMs();
        if (e.observations != k + 1) throw std::logic_error("bench map-size: estimate out of step");
      }
      c.compare = summarize(window_compare_ms);
      c.rest = summarize(window_rest_ms);
      window_compare_ms.clear();
      window_rest_ms.clear();
      c.comparisons = window_comparisons / static_cast<double>(window_ms.size());
      window_comparisons = 0;
      c.rss_mb = static_cast<double>(residentBytes()) / (1024.0 * 1024.0);
      c.index_mb = static_cast<double>(filter.memoryStats().candidate_index_bytes) / (1024.0 * 1024.0);
      c.compared = window_compared;
      c.agreed = window_agreed;
      c.confident = window_confident;
      c.confident_agreed = window_confident_agreed;
      checkpoints.push_back(c);
      window_ms.clear();
      window_compared = window_agreed = window_confident = window_confident_agreed = 0;
      if (!o.json) {
        std::printf("%8d %8zu %10.2f %10.2f %10.2f %8.1f %9.1f %9.0f %8d of %3d %8d of %3d %8.2f %8.2f %8.2f\n", c.steps,
                    c.stored, c.step.median_ms, c.step.p99_ms, c.step.max_ms, c.rss_mb, c.index_mb, c.comparisons,
                    c.agreed, c.compared, c.confident_agreed, c.confident, c.compare.median_ms, c.rest.median_ms,
                    c.estimate_ms);
        std::fflush(stdout);
      }
    }
  }
  const double peak_mb = static_cast<double>(peakResidentBytes()) / (1024.0 * 1024.0);
  const MapFileTimes map_file = o.map_file ? timeMapFile(filter, similarity) : MapFileTimes{};
  const double share = compared > 0 ? static_cast<double>(agreed) / compared : 1.0;
  if (o.json) {
    JsonWriter json(std::cout);
    json.beginObject();
    json.field("steps", o.places).field("particles", o.particles).field("indexed_steps", filter.indexedSteps());
    json.field("exhaustive_up_to", o.candidates.exhaustive_up_to).field("candidates", o.candidates.candidates);
    json.field("background_samples", o.candidates.background_samples);
    json.field("decisions_compared", compared).field("decisions_same", agreed).field("same_share", share);
    json.field("confident_compared", confident).field("confident_same", confident_agreed);
    if (o.control) json.field("control_same", control_same).field("control_confident_same", control_confident_same);
    json.field("peak_rss_mb", peak_mb);
    if (o.map_file) {
      json.key("map_file").beginObject();
      json.field("megabytes", map_file.megabytes).field("snapshot_ms", map_file.snapshot_ms);
      json.field("encode_ms", map_file.encode_ms).field("encode_cpu_ms", map_file.encode_cpu_ms);
      json.field("write_ms", map_file.write_ms);
      json.field("load_ms", map_file.load_ms).field("load_cpu_ms", map_file.load_cpu_ms).field("loaded_observations", map_file.loaded_observations);
      json.endObject();
    }
    json.key("checkpoints").beginArray();
    for (const Checkpoint& c : checkpoints) {
      json.beginObject();
      json.field("steps", c.steps).field("stored", c.stored).field("median_ms", c.step.median_ms);
      json.field("p99_ms", c.step.p99_ms).field("max_ms", c.step.max_ms).field("rss_mb", c.rss_mb);
      json.field("compare_median_ms", c.compare.median_ms).field("rest_median_ms", c.rest.median_ms);
      json.field("estimate_ms", c.estimate_ms);
      json.field("index_mb", c.index_mb).field("comparisons_per_step", c.comparisons).field("compared", c.compared).field("same", c.agreed);
      json.field("confident", c.confident).field("confident_same", c.confident_agreed);
      json.endObject();
    }
    json.endArray();
    json.endObject();
    std::cout << "\n";
  } else {
    std::printf("decisions equal to the exhaustive comparison's: %d of %d (%.1f %%); where the exhaustive decision "
                "has p >= 0.5: %d of %d (%.1f %%); indexed steps %lld; peak RSS %.1f MB\n",
                agreed, compared, 100.0 * share, confident_agreed, confident,
                confident > 0 ? 100.0 * confident_agreed / confident : 100.0, static_cast<long long>(filter.indexedSteps()),
                peak_mb);
    if (o.map_file)
      std::printf("map file of %d observations: %.1f MB; snapshot %.1f ms (topology thread, the frame path), encode "
                  "%.1f ms (CPU %.1f) and write %.1f ms (map writer thread); load %.1f ms (CPU %.1f)\n",
                  map_file.loaded_observations, map_file.megabytes, map_file.snapshot_ms, map_file.encode_ms,
                  map_file.encode_cpu_ms, map_file.write_ms, map_file.load_ms, map_file.load_cpu_ms);
    if (o.control)
      std::printf("control, exhaustive with similarities nudged by 1e-6 against exhaustive: %d of %d the same (%.1f "
                  "%%); where decided: %d of %d\n",
                  control_same, compared, compared > 0 ? 100.0 * control_same / compared : 100.0,
                  control_confident_same, control_confident);
  }
  if (!o.svg.empty()) {
    SvgPlot time;
    time.title = "ms per new place (" + std::to_string(o.particles) + " particles) against map size";
    time.x_label = "places in the map (steps)";
    time.y_label = "ms per step";
    time.series.push_back(SvgSeries{"ms per step, median per 1 % of the run", plot_x, plot_median, "#1f77b4", 1.5});
    time.series.push_back(SvgSeries{"ms per step, p99 per 1 % of the run", plot_x, plot_p99, "#9ecae1", 1.0});
    time.series.push_back(
        SvgSeries{"ms per step outside the exact comparisons, median per 1 %", plot_x, plot_rest, "#2ca02c", 1.5});
    time.y_min = 0.0;
    time.y_max = 60.0;  // a step stalled by the machine (p99 of a window) is drawn at the top edge
    for (SvgSeries& s : time.series)
      for (double& y : s.y) y = std::min(y, *time.y_max);
    time.horizontal_lines.push_back(SvgLine{20.0, "#1f77b4", true, "20 ms (median target)"});
    time.horizontal_lines.push_back(SvgLine{40.0, "#9ecae1", true, "40 ms (p99 target)"});
    if (o.candidates.exhaustive_up_to < o.places)
      time.vertical_lines.push_back(SvgLine{static_cast<double>(o.candidates.exhaustive_up_to), "#555555", true,
                                            "index from here (stored representatives)"});
    std::ofstream(o.svg) << renderSvgLinePlot(time);
    SvgPlot memory;
    memory.title = "resident MB against map size (" + std::to_string(o.particles) + " particles)";
    memory.x_label = "places in the map (steps)";
    memory.y_label = "MB resident (VmRSS)";
    memory.series.push_back(SvgSeries{"resident MB (VmRSS)", plot_x, plot_rss, "#d62728", 2.0});
    memory.horizontal_lines.push_back(SvgLine{500.0, "#d62728", true, "500 MB (target)"});
    memory.y_min = 0.0;
    const std::string memory_svg = memoryPlotPath(o.svg);
    std::ofstream(memory_svg) << renderSvgLinePlot(memory);
    if (!o.json) std::printf("plots: %s, %s\n", o.svg.c_str(), memory_svg.c_str());
  }
}

}  // namespace

void addBenchMapSize(CLI::App& bench) {
  auto o = std::make_shared<MapSizeBenchOptions>();
  o->samples = defaultSamplesFolder();
  auto* cmd = bench.add_subcommand("map-size", "ms and resident MB per new place as the map grows, decisions against "
                                               "the exhaustive comparison, the map file's save and load");
  cmd->add_option("--places", o->places, "Steps (places met)")->check(CLI::Range(2, 1000000))->capture_default_str();
  cmd->add_option("--particles", o->particles, "Particles")->check(CLI::Range(1, 1000000))->capture_default_str();
  cmd->add_option("--checkpoint", o->checkpoint, "Print every N steps")->check(CLI::Range(1, 1000000))->capture_default_str();
  cmd->add_option("--compare-every", o->compare_every, "Compare the decision with the exhaustive one every N steps (0: never)")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  cmd->add_option("--revisit-share", o->revisit_share, "Chance that the route goes back over earlier places")
      ->check(CLI::Range(0.0, 0.95))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the route, the synthetic places and the filter")->capture_default_str();
  cmd->add_option("--exhaustive-up-to", o->candidates.exhaustive_up_to, "Compared exhaustively up to N stored")
      ->check(CLI::Range(0, 1000000000))
      ->capture_default_str();
  cmd->add_option("--candidates", o->candidates.candidates, "Candidates compared exactly")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--background-samples", o->candidates.background_samples, "Background samples")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  cmd->add_option("--samples", o->samples, "Frames whose fingerprints the synthetic places are made of")
      ->capture_default_str();
  cmd->add_option("--svg", o->svg, "Write the plot of ms per step against map size here (and of MB to NAME-memory.svg)");
  cmd->add_flag("--json", o->json, "JSON instead of the table");
  cmd->add_flag("!--no-map-file", o->map_file, "Skip saving and loading the map at the end");
  cmd->add_flag("--control", o->control,
                "Also step a second exhaustive fork whose similarities differ by a relative 1e-6: how often the "
                "filter's own decision survives a change that small");
  cmd->callback([o] { runMapSizeBench(*o); });
}

}  // namespace toposlam::cli
