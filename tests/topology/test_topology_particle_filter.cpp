// Tests of TopologyParticleFilter (thesis chapter 5): the model's numbers, loop closing over two
// traversals, look-alike places, Bell-number completeness, determinism, slicing, sharing.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <set>
#include <sstream>
#include <vector>

#include "fake_similarity.hpp"
#include "toposlam/topology/map_store.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

using namespace toposlam;
using toposlam::test::placeSimilarity;
using toposlam::test::taggedFingerprint;
using toposlam::test::TagSimilarity;

namespace {

TopologyFilterConfig configWith(int particles, std::uint64_t seed) {
  TopologyFilterConfig c;
  c.particles = particles;
  c.seed = seed;
  return c;
}

void run(TopologyParticleFilter& filter, const std::vector<int>& places) {
  for (int p : places) filter.step(taggedFingerprint(p));
}

/// The relative likelihood of the default preset's kind: slope 2, the given offset, eq. 5.7's entropy or not.
TopologyFilterConfig relativeConfig(double offset, bool entropy) {
  TopologyFilterConfig config = configWith(500, 1);
  config.likelihood = LikelihoodModel::Relative;
  config.relative_slope = 2.0;
  config.relative_offset = offset;
  config.new_node_entropy = entropy;
  return config;
}

std::string stateBytes(const TopologyParticleFilter& filter) {
  std::ostringstream out;
  filter.saveState(out);
  return out.str();
}

std::vector<int> route(int places, int traversals) {
  std::vector<int> r;
  for (int t = 0; t < traversals; ++t) {
    for (int p = 0; p < places; ++p) r.push_back(p);
  }
  return r;
}

}  // namespace

TEST_CASE(
    "GIVEN the thesis' gamma(k = 10, theta = 0.25) WHEN evaluated at x = j + 1 THEN Figure 5.3's weights",
    "[topology]") {
  const std::array<double, 5> expected{0.053, 0.496, 0.350, 0.085, 0.012};
  for (int j = 0; j < 5; ++j)
    CHECK(gammaPdf(j + 1.0, 10.0, 0.25) == Approx(expected[static_cast<std::size_t>(j)]).margin(0.0006));

  const KnownNodeTransition t = knownNodeTransition(TopologyFilterConfig{});
  double gamma_total = t.stay;
  for (double w : t.successor) gamma_total += w;
  CHECK(gamma_total == Approx(0.95).epsilon(1e-12));
  CHECK(t.new_node == 0.05);
  REQUIRE(t.successor.size() == 5);
  CHECK(t.stay == Approx(0.95 * 0.0529 / 0.9977).margin(0.001));
  CHECK(t.successor[0] == Approx(0.4727).margin(0.001));  // 0.496 * 0.95 / 0.9977
}

TEST_CASE(
    "GIVEN Figure 5.2's known-node likelihoods WHEN the new-node likelihood is computed THEN (1 - 0.4) * "
    "0.85",
    "[topology]") {
  const std::vector<double> likelihoods{0.1, 0.05, 0.4, 0.2, 0.1};
  CHECK(normalisedEntropy(likelihoods) == Approx(0.848).margin(0.001));
  CHECK(newNodeLikelihood(likelihoods) == Approx(0.509).margin(0.001));  // thesis rounds to 0.51
  const std::vector<double> single{0.7};
  CHECK(normalisedEntropy(single) == 1.0);  // eta = 1 with one known node
  CHECK(newNodeLikelihood(single) == Approx(0.3));
  const std::vector<double> uniform{0.3, 0.3, 0.3};
  CHECK(normalisedEntropy(uniform) == Approx(1.0));
  const std::vector<double> peaked{0.9, 0.0, 0.0};
  CHECK(normalisedEntropy(peaked) == Approx(0.0).margin(1e-12));
}

TEST_CASE("GIVEN bad configs WHEN validated THEN the key and its range are named", "[topology]") {
  TopologyFilterConfig c;
  CHECK(c.validate().empty());
  c.particles = 0;
  CHECK(c.validate().rfind("particles:", 0) == 0);
  c = {};
  c.alpha = -1;
  CHECK(c.validate().rfind("alpha:", 0) == 0);
  c = {};
  c.max_successors = 9;
  CHECK(c.validate().rfind("max_successors:", 0) == 0);
  c = {};
  c.max_representatives_per_node = 0;
  CHECK(c.validate().rfind("max_representatives_per_node:", 0) == 0);
  auto sim = placeSimilarity();
  CHECK_THROWS_AS(TopologyParticleFilter(c, sim), std::invalid_argument);
}

TEST_CASE(
    "GIVEN a flat similarity WHEN two observations are filtered THEN eq. 5.8 proposes staying with 1 / (1 + "
    "alpha)",
    "[topology]") {
  auto sim = TagSimilarity([](int, int) { return 0.5; });
  TopologyParticleFilter filter(configWith(20000, 3), sim);
  run(filter, {0, 1});
  int stayed = 0;
  for (int i = 0; i < 20000; ++i) stayed += filter.particleAssignment(i) == std::vector<int>{0, 0} ? 1 : 0;
  CHECK(stayed / 20000.0 == Approx(1.0 / 16.0).margin(0.006));
  CHECK(filter.lastEffectiveSampleSize() == Approx(20000.0).epsilon(1e-9));  // equal weights
}

TEST_CASE(
    "GIVEN a flat similarity and many particles WHEN 4 observations are filtered THEN all B_4 = 15 "
    "topologies appear",
    "[topology][bell]") {
  auto sim = TagSimilarity([](int, int) { return 0.5; });
  for (bool forbid : {false, true}) {
    std::set<std::vector<int>> seen;
    int abab = 0, aba = 0;
    for (std::uint64_t seed : {1u, 2u, 3u}) {
      TopologyFilterConfig c = configWith(20000, seed);
      c.forbid_return_to_previous = forbid;
      TopologyParticleFilter filter(c, sim);
      run(filter, {0, 1, 2, 3});
      for (int i = 0; i < c.particles; ++i) {
        const std::vector<int> a = filter.particleAssignment(i);
        // A topology is a restricted growth string: each node is at most one more than the largest before.
        int largest = -1;
        for (int n : a) {
          REQUIRE(n <= largest + 1);
          largest = std::max(largest, n);
        }
        seen.insert(a);
        if (a[0] == 0 && a[1] == 1 && a[2] == 0) {
          ++aba;
          abab += a[3] == 1 ? 1 : 0;
        }
      }
    }
    if (!forbid) {
      CHECK(seen.size() == 15);  // Bell number B_4
      // From A with successor list [B]: the 1st successor gets 0.496 * 0.95 / 0.9977.
      CHECK(static_cast<double>(abab) / aba == Approx(0.4727).margin(0.03));
    } else {
      CHECK(seen.size() == 14);  // A B A B needs the move back to the previous node
      CHECK(abab == 0);
    }
  }
}

TEST_CASE(
    "GIVEN two traversals of a synthetic route WHEN filtered THEN the second closes the loop onto the same "
    "nodes",
    "[topology]") {
  auto sim = placeSimilarity(0.9, 0.1);
  const std::vector<int> places = route(8, 2);
  for (std::uint64_t seed : {1u, 7u, 42u}) {
    TopologyParticleFilter filter(configWith(500, seed), sim);
    run(filter, places);
    const TopologyEstimate e = filter.estimate();
    CHECK(e.best.assignment == places);  // nodes 0..7, then 0..7 again
    CHECK(e.best.node_count == 8);
    CHECK(e.best.probability > 0.5);
    CHECK(e.current_node == 7);
    CHECK(e.current_node_probability >= e.best.probability);
    CHECK(e.effective_sample_size > 0.0);
    CHECK(e.effective_sample_size <= 500.0);
    REQUIRE_FALSE(e.locations.empty());
    CHECK(e.locations[0].founding_observation == 7);
    CHECK(e.locations[0].node_in_best == 7);
  }
}

TEST_CASE(
    "GIVEN a route through look-alike places WHEN filtered THEN several hypotheses live until the path tells "
    "them apart",
    "[topology]") {
  // Places 2 and 5 look the same. First traversal 0..7, then the second traversal.
  auto looks = [](int p) { return p == 5 ? 2 : p; };
  auto sim = TagSimilarity([&](int a, int b) { return looks(a) == looks(b) ? 0.9 : 0.1; });
  int kept_both = 0, recovered = 0;
  const std::vector<std::uint64_t> seeds{1, 2, 3, 4, 5};
  for (std::uint64_t seed : seeds) {
    TopologyParticleFilter filter(configWith(500, seed), sim);
    run(filter, {0, 1, 2, 3, 4, 5});
    // Observation 5 is either the first visit of place 5 or a return to node 2.
    const TopologyEstimate ambiguous = filter.estimate();
    double first_visit = 0.0, return_to_2 = 0.0;
    for (const auto& l : ambiguous.locations) {
      if (l.founding_observation == 5) first_visit = l.probability;
      if (l.founding_observation == 2) return_to_2 = l.probability;
    }
    INFO("seed " << seed << ": new " << first_visit << ", node 2 " << return_to_2);
    kept_both += first_visit >= 0.2 && return_to_2 >= 0.2 ? 1 : 0;
    // Place 6 is new: a return to node 2 predicted node 3 next, so that hypothesis fades.
    filter.step(taggedFingerprint(6));
    const TopologyEstimate told = filter.estimate();
    CHECK(told.best.assignment == std::vector<int>{0, 1, 2, 3, 4, 5, 6});
    CHECK(told.best.probability > 0.5);
    // The second traversal.
    run(filter, {7, 0, 1, 2, 3, 4, 5, 6, 7});
    const TopologyEstimate e = filter.estimate();
    const std::vector<int> truth{0, 1, 2, 3, 4, 5, 6, 7, 0, 1, 2, 3, 4, 5, 6, 7};
    recovered += e.best.assignment == truth && e.best.probability > 0.3 ? 1 : 0;
  }
  CHECK(kept_both == static_cast<int>(seeds.size()));
  CHECK(recovered == static_cast<int>(seeds.size()));
}

TEST_CASE("GIVEN the same input and seed WHEN run twice THEN the states are identical bit for bit",
          "[topology]") {
  auto sim = placeSimilarity(0.8, 0.2);
  const std::vector<int> places = route(6, 3);
  TopologyParticleFilter a(configWith(300, 11), sim), b(configWith(300, 11), sim),
      c(configWith(300, 12), sim);
  run(a, places);
  run(b, places);
  run(c, places);
  CHECK(stateBytes(a) == stateBytes(b));
  CHECK(stateBytes(a) != stateBytes(c));
}

TEST_CASE("GIVEN a step run in slices WHEN compared with whole steps THEN every state is identical",
          "[topology][slice]") {
  auto sim = placeSimilarity(0.8, 0.15);
  const std::vector<int> places = route(7, 3);
  TopologyParticleFilter whole(configWith(200, 5), sim), sliced(configWith(200, 5), sim);
  int max_slices = 0;
  for (std::size_t k = 0; k < places.size(); ++k) {
    whole.step(taggedFingerprint(places[k]));
    sliced.beginStep(taggedFingerprint(places[k]));
    CHECK(sliced.stepInProgress());
    CHECK_THROWS_AS(sliced.beginStep(taggedFingerprint(0)), std::logic_error);
    std::ostringstream sink;
    CHECK_THROWS_AS(sliced.saveState(sink), std::logic_error);
    int slices = 1;
    while (!sliced.advance(7 + k % 5)) ++slices;
    max_slices = std::max(max_slices, slices);
    REQUIRE(stateBytes(whole) == stateBytes(sliced));
    CHECK(whole.lastEffectiveSampleSize() == sliced.lastEffectiveSampleSize());
  }
  CHECK(max_slices >= 3 * 200 / 11);  // propose + update alone are 400 items
  CHECK(sliced.advance(1));           // no step in progress
  CHECK_THROWS_AS(sliced.advance(0), std::invalid_argument);
}

TEST_CASE(
    "GIVEN 500 particles WHEN a step runs THEN each stored representative is compared once, not once per "
    "particle",
    "[topology]") {
  auto sim = placeSimilarity(0.9, 0.1);
  TopologyParticleFilter filter(configWith(500, 2), sim);
  const std::vector<int> places = route(10, 2);
  for (std::size_t k = 0; k < places.size(); ++k) {
    const long before = sim.calls();
    filter.step(taggedFingerprint(places[k]));
    CHECK(sim.calls() - before <= static_cast<long>(k));  // at most one per earlier observation
  }
}

TEST_CASE(
    "GIVEN a cap of 2 representatives WHEN one place is seen 7 times THEN only the newest 2 are compared",
    "[topology]") {
  auto sim = TagSimilarity([](int, int) { return 1.0; });  // the same place: a new node has likelihood 0
  TopologyFilterConfig c = configWith(500, 9);
  c.max_representatives_per_node = 2;
  TopologyParticleFilter filter(c, sim);
  run(filter, {0, 0, 0, 0, 0, 0});
  for (int i = 0; i < c.particles; ++i) REQUIRE(filter.particleAssignment(i) == std::vector<int>(6, 0));
  const long before = sim.calls();
  filter.step(taggedFingerprint(0));
  CHECK(sim.calls() - before == 2);  // observations 4 and 5
  for (int o = 0; o < 4; ++o) CHECK(filter.storedRepresentative(o) == nullptr);
  CHECK(filter.storedRepresentative(4) != nullptr);
  CHECK(filter.storedRepresentative(6) != nullptr);
}

TEST_CASE(
    "GIVEN 500 particles and 300 observations WHEN the shared structures are counted THEN they do not grow "
    "with particles x history",
    "[topology][memory]") {
  auto sim = placeSimilarity(0.7, 0.2);
  TopologyParticleFilter filter(configWith(500, 4), sim);
  run(filter, route(30, 10));
  const TopologyMemoryStats stats = filter.memoryStats();
  INFO("states " << stats.distinct_states << " records " << stats.history_records << " trie "
                 << stats.trie_nodes);
  CHECK(stats.distinct_states <= 500);
  // Particles x history would be 150000 records: the lineages share their past.
  CHECK(stats.history_records < 300 + 20 * 500);
  CHECK(stats.trie_nodes < 20 * 500);
  CHECK(stats.stored_fingerprints <= 300);
}

TEST_CASE(
    "GIVEN a filter saved mid-run WHEN loaded and continued THEN it ends exactly like a run that never "
    "stopped",
    "[topology][persistence]") {
  auto sim = placeSimilarity(0.85, 0.1);
  const std::vector<int> places = route(9, 3);
  TopologyParticleFilter straight(configWith(300, 21), sim);
  run(straight, places);

  TopologyParticleFilter first(configWith(300, 21), sim);
  run(first, std::vector<int>(places.begin(), places.begin() + 13));
  const std::string file = MapStore::encode(first, "app");
  LoadedMap loaded = MapStore::decode(file, sim);
  CHECK(loaded.application_data == "app");
  CHECK(MapStore::encode(*loaded.filter, "app") == file);  // the reload is exact
  run(*loaded.filter, std::vector<int>(places.begin() + 13, places.end()));
  CHECK(stateBytes(*loaded.filter) == stateBytes(straight));
  CHECK(loaded.filter->estimate().best.assignment == straight.estimate().best.assignment);
}

TEST_CASE("GIVEN similarities among stored representatives WHEN made relative THEN the likelihood follows the z-score",
          "[topology][relative]") {
  // Leave-one-out z against 4 others at 0.02, 0.03, 0.04, 0.05 (mean 0.035, std 0.0112, above the floor).
  const double sum = 0.14, sum_sq = 0.02 * 0.02 + 0.03 * 0.03 + 0.04 * 0.04 + 0.05 * 0.05;
  const double z = (0.2 - 0.035) / std::sqrt(sum_sq / 4 - 0.035 * 0.035);
  CHECK(relativeLikelihood(0.2, sum, sum_sq, 4, 2.0, 8.0, 0.02) ==
        Approx(1.0 / (1.0 + std::exp(-2.0 * ((0.2 - 0.035) / 0.02 - 8.0)))));  // std 0.0112 < floor 0.02
  CHECK(z > 14.0);
  CHECK(relativeLikelihood(0.035, sum, sum_sq, 4, 2.0, 8.0, 0.02) < 1e-6);  // an average one: no evidence
  // No other representative: z = 0.
  CHECK(relativeLikelihood(0.9, 0.0, 0.0, 0, 2.0, 8.0, 0.02) == Approx(1.0 / (1.0 + std::exp(16.0))));
  CHECK(parseLikelihoodModel("relative") == LikelihoodModel::Relative);
  CHECK_THROWS_AS(parseLikelihoodModel("bayes"), std::invalid_argument);
}

TEST_CASE(
    "GIVEN a revisit at real similarity levels WHEN filtered THEN the relative likelihood closes the loop and the "
    "thesis' absolute one cannot",
    "[topology][relative]") {
  // Real frames: a revisit scores about 0.3, other places 0.01-0.06 (docs/topology.md). Two laps of 8.
  auto sim = TagSimilarity([](int a, int b) { return a == b ? 0.3 : 0.01 + 0.01 * ((a * 7 + b * 3) % 6); });
  const std::vector<int> places = route(8, 2);
  for (std::uint64_t seed : {1u, 7u}) {
    TopologyFilterConfig relative = configWith(500, seed);
    relative.likelihood = LikelihoodModel::Relative;
    relative.relative_slope = 2.0;
    relative.relative_offset = 8.0;
    TopologyParticleFilter with_relative(relative, sim);
    run(with_relative, places);
    CHECK(with_relative.estimate().best.assignment == places);
    CHECK(with_relative.estimate().best.probability > 0.5);
    TopologyParticleFilter with_absolute(configWith(500, seed), sim);
    run(with_absolute, places);
    CHECK(with_absolute.estimate().best.node_count == 16);  // every place a new node: no closure
  }
}

TEST_CASE(
    "GIVEN one weak standout among relative likelihoods WHEN a new node's likelihood takes eq. 5.7's entropy THEN "
    "the weak match wins the particles, and with 1 - max L a new node does",
    "[topology][relative]") {
  // The look-alike rooms' step 6 (docs/topology.md, "The new node's likelihood"): the new place scores 0.42
  // with place 0 and 0.00-0.15 with the other five, a leave-one-out z of about 6.
  const std::array<double, 6> to_last{0.4216, 0.1527, 0.0, 0.0576, 0.0899, 0.004};
  const test::TagSimilarity sim([&](int a, int b) {
    if (a == b) return 1.0;
    if (std::max(a, b) == 6) return to_last[static_cast<std::size_t>(std::min(a, b))];
    return 0.01 + 0.01 * ((a * 7 + b * 3) % 5);
  });
  const auto lastStep = [&](bool entropy, double offset) {
    TopologyParticleFilter filter(relativeConfig(offset, entropy), sim);
    run(filter, {0, 1, 2, 3, 4, 5, 6});
    const TopologyEstimate e = filter.estimate(0);
    REQUIRE(e.best.assignment.size() == 7);
    return std::pair<int, double>(e.best.assignment.back(), e.best.probability);
  };
  // Offset 8: the match's likelihood is about 0.035, yet with the entropy it takes nearly every particle.
  const auto [with_entropy, p_with] = lastStep(true, 8.0);
  CHECK(with_entropy == 0);
  CHECK(p_with > 0.9);
  const auto [without, p_without] = lastStep(false, 8.0);
  CHECK(without == 6);
  CHECK(p_without > 0.9);
  // The default preset's offset 4.25: the match's likelihood is about 0.98 and the closure is proposed, but
  // the new-node hypothesis keeps a share (the look-alike rooms undo it with the next place).
  const auto [preset, p_preset] = lastStep(false, 4.25);
  CHECK(preset == 0);
  CHECK(p_preset > 0.5);
  CHECK(p_preset < 0.95);
}

TEST_CASE("GIVEN evidence from outside the representatives WHEN a step takes it THEN a revisit the appearance cannot "
          "tell wins, and bad evidence is refused",
          "[topology][evidence]") {
  // Every representative looks the same to the similarity (0.3): on appearance alone the third observation
  // cannot tell observation 0's node from a new one. Sequence evidence 0.99 on observation 0 decides it.
  const test::TagSimilarity flat([](int, int) { return 0.3; });
  TopologyFilterConfig config;
  config.particles = 200;
  config.likelihood = LikelihoodModel::Relative;
  config.relative_slope = 2.0;
  config.relative_offset = 8.0;
  const auto run = [&](bool with_evidence) {
    TopologyParticleFilter filter(config, flat);
    filter.step(test::taggedFingerprint(0));
    filter.step(test::taggedFingerprint(1));
    const std::vector<double> evidence{0.99, 0.0};
    filter.step(test::taggedFingerprint(2), with_evidence ? std::span<const double>(evidence) : std::span<const double>());
    return filter.estimate(0).best.assignment;
  };
  CHECK(run(false) == std::vector<int>{0, 1, 2});
  CHECK(run(true) == std::vector<int>{0, 1, 0});

  TopologyParticleFilter filter(config, flat);
  filter.step(test::taggedFingerprint(0));
  const std::vector<double> too_long{0.5, 0.5};
  CHECK_THROWS_WITH(filter.beginStep(test::taggedFingerprint(1), too_long), Catch::Matchers::Contains("evidence for 2 observations"));
  // Not finite or out of [0, 1]: clamped, never a NaN weight.
  const std::vector<double> odd{std::numeric_limits<double>::quiet_NaN()};
  filter.step(test::taggedFingerprint(1), odd);
  CHECK(filter.observationCount() == 2);
}

TEST_CASE(
    "GIVEN estimate() called after every step (its memo of the last best topology warm) WHEN compared with the "
    "estimate of a loaded copy (no memo) and with the particles' own assignments THEN they are identical",
    "[topology]") {
  // Look-alike places (same tag modulo 3): the best topology changes lineage now and then.
  auto sim = TagSimilarity([](int a, int b) { return a == b ? 0.8 : (a % 3 == b % 3 ? 0.6 : 0.1); });
  TopologyParticleFilter warm(configWith(200, 5), sim);
  const std::vector<int> places = route(7, 3);
  int alternatives_checked = 0, best_changed_lineage = 0;
  std::vector<int> previous_best;
  for (const int place : places) {
    warm.step(taggedFingerprint(place));
    const TopologyEstimate e = warm.estimate(4);
    std::istringstream in(stateBytes(warm));
    const auto cold = TopologyParticleFilter::loadState(in, sim);
    const TopologyEstimate c = cold->estimate(4);
    REQUIRE(e.best.assignment == c.best.assignment);
    REQUIRE(e.best.probability == c.best.probability);
    REQUIRE(e.alternatives.size() == c.alternatives.size());
    for (std::size_t k = 0; k < e.alternatives.size(); ++k) {
      REQUIRE(e.alternatives[k].assignment == c.alternatives[k].assignment);
      REQUIRE(e.alternatives[k].first_difference == c.alternatives[k].first_difference);
      REQUIRE(e.alternatives[k].probability == c.alternatives[k].probability);
    }
    REQUIRE(e.locations.size() == c.locations.size());
    // Every topology reported is some particle's, in full; the first difference is the first index where it
    // differs from the best; a location's node in the best topology is the node first seen there.
    std::vector<std::vector<int>> held;
    for (int i = 0; i < warm.config().particles; ++i) held.push_back(warm.particleAssignment(i));
    REQUIRE(std::find(held.begin(), held.end(), e.best.assignment) != held.end());
    for (const TopologyHypothesis& h : e.alternatives) {
      REQUIRE(std::find(held.begin(), held.end(), h.assignment) != held.end());
      const auto diff = std::mismatch(h.assignment.begin(), h.assignment.end(), e.best.assignment.begin());
      REQUIRE(h.first_difference == (diff.first == h.assignment.end() ? -1 : static_cast<int>(diff.first - h.assignment.begin())));
      ++alternatives_checked;
    }
    for (std::size_t k = 0; k < e.locations.size(); ++k) {
      const LocationHypothesis& l = e.locations[k];
      REQUIRE(l.founding_observation == c.locations[k].founding_observation);
      REQUIRE(l.node_in_best == c.locations[k].node_in_best);
      const auto& a = e.best.assignment;
      const int node = a[static_cast<std::size_t>(l.founding_observation)];
      const bool founded_there = std::find(a.begin(), a.end(), node) - a.begin() == l.founding_observation;
      REQUIRE(l.node_in_best == (founded_there ? node : -1));
    }
    if (!previous_best.empty() &&
        !std::equal(previous_best.begin(), previous_best.end(), e.best.assignment.begin()))
      ++best_changed_lineage;
    previous_best = e.best.assignment;
  }
  CHECK(alternatives_checked > 20);
  CHECK(best_changed_lineage > 0);  // the memo's shared prefix was not always the whole last best
}

TEST_CASE(
    "GIVEN a place that looks exactly like a stored one WHEN a new node's likelihood has a floor THEN the closure is "
    "proposed and the next place undoes it, and without the floor it is kept",
    "[topology][relative]") {
  // The look-alike rooms (docs/topology.md, "Look-alike rooms"): places 0-5 differ, place 6 is place 0's twin
  // (relative likelihood ~1 for node 0), place 7 matches nothing. From node 0 the next place should be node 1;
  // from a new node, "new" is what eq. 5.8 expects.
  const test::TagSimilarity sim([](int a, int b) {
    if (a == b) return 1.0;
    if (std::min(a, b) == 0 && std::max(a, b) == 6) return 0.6;
    return 0.02 + 0.01 * ((a * 7 + b * 3) % 5);
  });
  const auto lap = [&](double new_node_probability, double floor) {
    TopologyFilterConfig config = relativeConfig(4.25, false);
    config.gamma_shape = 5.0;
    config.gamma_scale = 0.4;
    config.new_node_probability = new_node_probability;
    config.new_node_likelihood_floor = floor;
    TopologyParticleFilter filter(config, sim);
    run(filter, {0, 1, 2, 3, 4, 5, 6});
    const TopologyEstimate at_twin = filter.estimate(0);
    double kept_new = 0.0;  // share of particles that hold place 6 as a node of its own
    for (const LocationHypothesis& h : at_twin.locations)
      if (h.founding_observation == 6) kept_new = h.probability;
    filter.step(taggedFingerprint(7));
    const TopologyEstimate after = filter.estimate(0);
    REQUIRE(after.best.assignment.size() == 8);
    struct Outcome {
      int proposed;       // place 6's node in the best topology at its own step
      double kept_new;
      bool undone;        // after place 7, place 6 is not on place 0's node
    };
    return Outcome{at_twin.best.assignment.back(), kept_new,
                   after.best.assignment[6] != after.best.assignment[0]};
  };
  // The default preset's 0.02 and 0.01: the closure is proposed, about 1 particle in 10 keeps "new", and the
  // place after it moves the best topology there.
  const auto with_floor = lap(0.02, 0.01);
  CHECK(with_floor.proposed == 0);
  CHECK(with_floor.kept_new > 0.03);
  CHECK(with_floor.kept_new < 0.5);
  CHECK(with_floor.undone);
  // No floor (the thesis): a known node at L ~ 1 leaves "new" ~1e-4 of the weight; no particle keeps it.
  const auto without = lap(0.05, 0.0);
  CHECK(without.proposed == 0);
  CHECK(without.kept_new < 0.01);
  CHECK_FALSE(without.undone);
}

TEST_CASE("GIVEN a new node's likelihood floor below 0, at 1 or not a number WHEN validated THEN the key is named",
          "[topology]") {
  TopologyFilterConfig config;
  for (const double bad : {-0.01, 1.0, std::numeric_limits<double>::quiet_NaN()}) {
    config.new_node_likelihood_floor = bad;
    CHECK(config.validate() == "new_node_likelihood_floor: must be in [0, 1)");
  }
  config.new_node_likelihood_floor = 0.0;
  CHECK(config.validate().empty());
}

namespace {
/// Lap 1 stores places 0..7; lap 2's representatives are tags 100 + p, which score `representative` with
/// place p, and its samples tags 200 + p, which score 0.3 with it (a view of the same spot). Every other
/// pair scores 0.01-0.06, as different real places do.
test::TagSimilarity samplesSimilarity(double representative) {
  return test::TagSimilarity([representative](int a, int b) {
    const int lo = std::min(a, b), hi = std::max(a, b);
    if (a == b) return 1.0;
    if (lo < 100 && hi == lo + 100) return representative;
    if (lo < 100 && hi == lo + 200) return 0.3;
    return 0.01 + 0.01 * ((a * 7 + b * 3) % 6);
  });
}

/// The default preset's filter (src/config/method_preset.cpp), with the given seed.
TopologyFilterConfig defaultPresetConfig(std::uint64_t seed) {
  TopologyFilterConfig config = relativeConfig(4.25, false);
  config.seed = seed;
  config.gamma_shape = 5.0;
  config.gamma_scale = 0.4;
  config.new_node_probability = 0.02;
  config.new_node_likelihood_floor = 0.01;
  return config;
}

std::vector<int> runTwoLaps(TopologyParticleFilter& filter, int samples_per_place) {
  for (int p = 0; p < 8; ++p) filter.step(taggedFingerprint(p));
  for (int p = 0; p < 8; ++p) {
    const std::vector<std::shared_ptr<const Fingerprint>> samples(static_cast<std::size_t>(samples_per_place),
                                                                  taggedFingerprint(200 + p));
    filter.step(taggedFingerprint(100 + p), {}, samples);
  }
  return filter.estimate(0).best.assignment;
}
}  // namespace

TEST_CASE("GIVEN a revisit whose representative barely matches WHEN its place samples match THEN the relative "
          "likelihood closes the loop, and without samples it does not",
          "[topology][relative][samples]") {
  // The representative alone: z = (0.12 - 0.035) / 0.02 = 4.25, a likelihood of 0.5, too weak against a new
  // node's 1 - 0.5 at the prior of a revisit. A sample at 0.3 stands out by z = 13: sqrt(0.5 x 1) = 0.71.
  const auto sim = samplesSimilarity(0.12);
  const std::vector<int> closed = route(8, 2);
  for (std::uint64_t seed : {1u, 3u, 7u}) {
    INFO("seed " << seed);
    TopologyParticleFilter alone(defaultPresetConfig(seed), sim), with_samples(defaultPresetConfig(seed), sim);
    const std::vector<int> without = runTwoLaps(alone, 0);
    CHECK(*std::max_element(without.begin(), without.end()) == 15);  // every place a new node
    CHECK(runTwoLaps(with_samples, 3) == closed);
    CHECK(with_samples.estimate(0).best.probability > 0.35);
  }
  // Samples cannot close a place alone: with a representative that does not stand out at all (0.03),
  // matching samples leave every second-lap place a new node.
  const auto unrelated = samplesSimilarity(0.03);
  TopologyParticleFilter filter(defaultPresetConfig(1), unrelated);
  const std::vector<int> assignment = runTwoLaps(filter, 3);
  CHECK(*std::max_element(assignment.begin(), assignment.end()) == 15);
}

TEST_CASE("GIVEN place samples WHEN a step runs in slices THEN it is identical to a whole step, and the absolute "
          "likelihood ignores them",
          "[topology][samples][slice]") {
  const auto sim = samplesSimilarity(0.12);
  TopologyParticleFilter whole(defaultPresetConfig(1), sim), sliced(defaultPresetConfig(1), sim);
  for (int p = 0; p < 8; ++p) {
    whole.step(taggedFingerprint(p));
    sliced.step(taggedFingerprint(p));
  }
  int slices = 0;
  for (int p = 0; p < 8; ++p) {
    const std::vector<std::shared_ptr<const Fingerprint>> samples{taggedFingerprint(200 + p), nullptr,
                                                                  taggedFingerprint(300 + p)};
    whole.step(taggedFingerprint(100 + p), {}, samples);
    sliced.beginStep(taggedFingerprint(100 + p), {}, samples);
    while (!sliced.advance(5)) ++slices;
    REQUIRE(stateBytes(whole) == stateBytes(sliced));
  }
  CHECK(slices > 8 * 3);  // (1 + 2 samples) x 8 stored comparisons alone are 24 items a step

  TopologyParticleFilter absolute_with(configWith(200, 3), sim), absolute_without(configWith(200, 3), sim);
  for (int p = 0; p < 8; ++p) {
    absolute_with.step(taggedFingerprint(p));
    absolute_without.step(taggedFingerprint(p));
  }
  for (int p = 0; p < 8; ++p) {
    const std::vector<std::shared_ptr<const Fingerprint>> samples{taggedFingerprint(200 + p)};
    absolute_with.step(taggedFingerprint(100 + p), {}, samples);
    absolute_without.step(taggedFingerprint(100 + p));
  }
  CHECK(stateBytes(absolute_with) == stateBytes(absolute_without));
}
