// `toposlam-bench revisits`: what the per-frame answer (docs/topology.md, "The per-frame answer") costs per
// keyframe as the keyframes grow to 20,000 (issue 37: flat, not growing with every keyframe ever seen), and
// whether it still finds the revisits.
//
// The stream is synthetic but made of real fingerprints (synthetic_places.hpp): one keyframe a second,
// each an observation of a location of its own; every 30 keyframes the route either goes on to new
// locations or, with chance --revisit-share, goes back over 30 consecutive earlier ones. Up to
// --exhaustive-up-to keyframes every earlier keyframe is compared (the cost grows); beyond, the candidate
// index's finds, the live runs' next steps and a fixed sample (the cost stays). Printed per checkpoint:
// median and p99 ms of a keyframe over the window, similarities computed per keyframe, resident MB, and on
// the revisit stretches (after their first 5 keyframes) the answers right, wrong and missing; outside
// them, the matches published (all wrong). With --compare-up-to N a second detector that compares
// exhaustively runs beside it up to N keyframes and the share of equal answers is printed. Prints numbers,
// fails nothing.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core/utility.hpp>

#include "bench_stats.hpp"
#include "benchmarks.hpp"
#include "image_input.hpp"
#include "synthetic_places.hpp"
#include "toposlam/config/method_preset.hpp"
#include "toposlam/core/json_writer.hpp"
#include "toposlam/matching/ngram_similarity.hpp"
#include "toposlam/platform/process_resources.hpp"
#include "toposlam/topology/sequence_loop_closures.hpp"

namespace toposlam::cli {

namespace {

struct RevisitBenchOptions {
  int keyframes = 5000;
  int checkpoint = 1000;
  int compare_up_to = 0;
  double revisit_share = 0.3;
  std::uint64_t seed = 1;
  int exhaustive_up_to = -1;  ///< -1: the default's
  int scales = -1;            ///< -1: the default's
  double min_score = -1.0;    ///< -1: the default's
  std::string samples;
  bool json = false;
};

constexpr int kSegment = 30;  ///< keyframes between the route's choices

struct Window {
  std::vector<double> ms;
  std::int64_t comparisons = 0;
  int keyframes = 0;
  int right = 0, wrong = 0, missing = 0, false_matches = 0;
  int compared = 0, equal = 0;
};

void runRevisitBench(const RevisitBenchOptions& o) {
  cv::setNumThreads(1);
  const MethodPreset preset = methodPreset("default");
  const std::vector<Fingerprint> donors = donorFingerprints(o.samples, preset.fingerprint, "revisits");
  const NgramSimilarity similarity(preset.similarity);
  SequenceEvidenceConfig config = preset.sequence_evidence;
  if (o.exhaustive_up_to >= 0) config.exhaustive_up_to = o.exhaustive_up_to;
  if (o.scales > 0) config.loop.scales = o.scales;
  if (o.min_score >= 0.0) config.min_score = o.min_score;
  SequenceEvidenceConfig exhaustive = config;
  exhaustive.exhaustive_up_to = 1000000000;
  PlaceSequenceEvidence detector(config, similarity);
  auto twin = o.compare_up_to > 0 ? std::make_unique<PlaceSequenceEvidence>(exhaustive, similarity) : nullptr;

  std::mt19937_64 rng(o.seed);
  std::vector<Fingerprint> locations;      // prototypes, in the order first seen
  std::vector<int> location_of_keyframe;   // the route
  std::vector<bool> revisiting;            // keyframe on a revisit stretch (after its first 5)
  Window w;
  if (!o.json)
    std::printf("%9s %9s %9s %9s %8s %8s %8s %8s %8s %9s\n", "keyframes", "median ms", "p99 ms", "compared", "RSS MB",
                "right", "wrong", "missing", "false", "= exact");
  JsonWriter json(std::cout, false);
  if (o.json) json.beginArray();
  int segment_start = 0;
  for (int k = 0; k < o.keyframes; ++k) {
    if (k % kSegment == 0) {
      const bool back = k >= 3 * kSegment && uniform(rng) < o.revisit_share;
      segment_start = back ? static_cast<int>(rng() % static_cast<std::uint64_t>(locations.size() - kSegment)) : -1;
    }
    int location;
    if (segment_start >= 0) {
      location = segment_start + k % kSegment;
    } else {
      locations.push_back(prototypeOf(donors[rng() % donors.size()], rng));
      location = static_cast<int>(locations.size()) - 1;
    }
    location_of_keyframe.push_back(location);
    const bool on_revisit = segment_start >= 0 && k % kSegment >= 5;
    const std::shared_ptr<const Fingerprint> observation = observationOf(locations[static_cast<std::size_t>(location)], rng);
    const std::int64_t before = detector.comparisons();
    const auto start = std::chrono::steady_clock::now();
    const FrameRevisit answer = detector.addFrame(k, static_cast<double>(k), observation);
    w.ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    w.comparisons += detector.comparisons() - before;
    ++w.keyframes;
    const bool right = answer.match_frame >= 0 &&
                       location_of_keyframe[static_cast<std::size_t>(answer.match_frame)] == location;
    if (on_revisit) {
      w.right += right ? 1 : 0;
      w.wrong += answer.match_frame >= 0 && !right ? 1 : 0;
      w.missing += answer.match_frame < 0 ? 1 : 0;
    } else if (segment_start < 0 && answer.match_frame >= 0) {
      ++w.false_matches;
    }
    if (twin && k < o.compare_up_to) {
      const FrameRevisit exact = twin->addFrame(k, static_cast<double>(k), observation);
      ++w.compared;
      w.equal += exact.match_frame == answer.match_frame ? 1 : 0;
    }
    if ((k + 1) % o.checkpoint == 0 || k + 1 == o.keyframes) {
      const TimingSummary t = summarize(w.ms);
      const double rss = static_cast<double>(residentBytes()) / (1024.0 * 1024.0);
      const double compared = static_cast<double>(w.comparisons) / std::max(1, w.keyframes);
      if (o.json) {
        json.beginObject().field("keyframes", k + 1).field("median_ms", t.median_ms).field("p99_ms", t.p99_ms)
            .field("compared_per_keyframe", compared).field("rss_mb", rss).field("right", w.right)
            .field("wrong", w.wrong).field("missing", w.missing).field("false_matches", w.false_matches)
            .field("compared_with_exact", w.compared).field("equal_to_exact", w.equal).endObject();
      } else {
        char equal[32] = "-";
        if (w.compared > 0) std::snprintf(equal, sizeof equal, "%d/%d", w.equal, w.compared);
        std::printf("%9d %9.2f %9.2f %9.0f %8.1f %8d %8d %8d %8d %9s\n", k + 1, t.median_ms, t.p99_ms, compared, rss,
                    w.right, w.wrong, w.missing, w.false_matches, equal);
        std::fflush(stdout);
      }
      w = Window{};
    }
  }
  if (o.json) {
    json.endArray();
    std::cout << "\n";
  }
}

}  // namespace

void addBenchRevisits(CLI::App& bench) {
  auto o = std::make_shared<RevisitBenchOptions>();
  o->samples = defaultSamplesFolder();
  auto* cmd = bench.add_subcommand("revisits", "ms per keyframe of the per-frame answer up to 20,000 keyframes, "
                                               "revisits found, answers against the exhaustive comparison");
  cmd->add_option("--keyframes", o->keyframes, "Keyframes (one a second)")->check(CLI::Range(2, 10000000))->capture_default_str();
  cmd->add_option("--checkpoint", o->checkpoint, "Print every N keyframes")->check(CLI::Range(1, 10000000))->capture_default_str();
  cmd->add_option("--compare-up-to", o->compare_up_to,
                  "Run an exhaustive detector beside it up to N keyframes and count equal answers (0: none)")
      ->check(CLI::Range(0, 10000000))
      ->capture_default_str();
  cmd->add_option("--exhaustive-up-to", o->exhaustive_up_to,
                  "Compare exhaustively up to N keyframes (default: topology.sequence_evidence.exhaustive_up_to)")
      ->check(CLI::Range(0, 1000000000));
  cmd->add_option("--scales", o->scales, "Memories side by side (default: topology.sequence_evidence.scales)")
      ->check(CLI::Range(1, 8));
  cmd->add_option("--min-score", o->min_score, "Published score (default: topology.sequence_evidence.min_score)")
      ->check(CLI::Range(0.0, 1e6));
  cmd->add_option("--revisit-share", o->revisit_share, "Chance that the route goes back over earlier locations")
      ->check(CLI::Range(0.0, 0.95))
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the route and the synthetic locations")->capture_default_str();
  cmd->add_option("--samples", o->samples, "Frames whose fingerprints the synthetic locations are made of")
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "JSON instead of the table");
  cmd->callback([o] { runRevisitBench(*o); });
}

}  // namespace toposlam::cli
