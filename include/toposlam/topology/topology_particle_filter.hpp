// Topological SLAM with a particle filter over topologies (thesis chapter 5, docs/topology.md).
//
// Every new place representative is one time step k. A particle is one hypothesis of the whole node
// assignment sequence L_1..L_k (a "topology": which observations show the same node). Per step:
//   1. each particle proposes its next node from the transition model: eq. 5.8 from a node without
//      adjacency information (never left yet), else the gamma(k = 10, theta = 0.25) model over "stay",
//      1st, 2nd, ... successor plus a fixed probability of a new node;
//   2. the similarity of the new representative with every representative still stored by some particle
//      is computed ONCE (SimilarityMeasure::similarity(reference = stored, query = new); above
//      CandidateSelectionConfig::exhaustive_up_to only with some of them, see there);
//   3. its weight is the appearance likelihood: for a known node m the max similarity over the
//      representatives this particle gave m; for a new node eta * (1 - max_m), eta the normalised entropy
//      of the normalised known-node likelihoods (eq. 5.6/5.7; eta = 1 with a single known node), or
//      1 - max_m without eta (new_node_entropy = false, the default preset's);
//   4. systematic resampling; 5. map update: the surviving particles append the representative to their
//      node, keeping at most max_representatives_per_node (the oldest is dropped).
//
// Successors (our reading, see docs/topology.md): successor j of node c is the j-th distinct node (other
// than c) the particle visited after it last left c, followed by the remembered successors of earlier
// visits, at most max_successors of them.
//
// Sharing: particles hold a pointer to an immutable, reference-counted topology state; states share their
// history (a linked list of assignment records) and their node tables (a persistent radix trie with path
// copying). Particles that propose the same node from the same state share one child state, so two
// particles hold the same state exactly when they agree on the whole assignment sequence. Per step, work
// and new memory are O(distinct states x (log N + max_successors^2) + stored representatives + M), never
// O(particles x history length). Likelihood aggregates are memoised per trie node and step.
//
// Determinism: all randomness comes from one std::mt19937_64 seeded from the config and saved with the
// map; the same input and seed give the same output bit for bit, however the step is sliced.
//
// Thread-safety: none; one instance per map, used from one thread. The SimilarityMeasure must outlive it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "toposlam/fingerprint/fingerprint.hpp"
#include "toposlam/matching/similarity_measure.hpp"
#include "toposlam/topology/place_candidate_index.hpp"
#include "toposlam/topology/topology_limits.hpp"

namespace toposlam {

namespace topology_detail {
struct TopologyState;
struct HistoryRecord;
class TrieNode;
}  // namespace topology_detail

/// How a stored representative's similarity with the new one becomes its appearance likelihood.
enum class LikelihoodModel : std::uint8_t {
  /// Thesis (eq. 5.5): the similarity itself.
  Absolute = 0,
  /// Per query, relative to the other stored representatives (docs/topology.md): z = (s - mean of the
  /// others) / max(std of the others, sigma_floor), likelihood = logistic(slope (z - offset)).
  Relative = 1,
};
const char* toString(LikelihoodModel model);
/// Parses "absolute" or "relative"; throws std::invalid_argument otherwise.
LikelihoodModel parseLikelihoodModel(const std::string& name);

/// The relative likelihood of one similarity among `others_count` others with sums `others_sum` and
/// `others_sum_sq` (leave-one-out statistics; others_count 0 gives z = 0).
double relativeLikelihood(double similarity, double others_sum, double others_sum_sq, int others_count,
                          double slope, double offset, double sigma_floor);

/// How step 1 compares the new representative once many are stored (issue 18, docs/topology.md "Large
/// maps"). Up to `exhaustive_up_to` stored representatives it is compared with every one (the thesis).
/// Above, a PlaceCandidateIndex over the stored descriptors picks the `candidates` most likely ones; those,
/// every stored representative the index cannot hold (no binary descriptors), every representative of a
/// known node some particle proposes this step (its likelihood is that particle's weight; the proposals
/// are drawn before the similarities, which they do not depend on), and `background_samples` others
/// spread evenly over the rest are compared exactly; every other stored representative is given
/// the mean similarity of those samples (the background), and the relative likelihood's spread includes
/// the samples' variance for them. Not saved with the map: it is how this process runs, not what the map is.
struct CandidateSelectionConfig {
  int exhaustive_up_to = 1000;  ///< stored representatives compared exhaustively; allowed [0, 1e9]
  int candidates = 100;         ///< compared exactly from the index's top; allowed [1, 100000]
  int background_samples = 100; ///< others compared exactly for the background; allowed [0, 100000]
  PlaceCandidateIndexConfig index;
  std::string validate() const;
};

struct TopologyFilterConfig {
  int particles = 500;                   ///< M (thesis: 500); allowed [1, 1000000]
  double alpha = 15.0;                   ///< prior map size of eq. 5.8 (thesis: 15); allowed (0, 1e6]
  double new_node_probability = 0.05;    ///< from a known node (thesis: "e.g. 0.05"); allowed (0, 1)
  double gamma_shape = 10.0;             ///< k of the successor gamma pdf (thesis: 10); allowed (0, 1000]
  double gamma_scale = 0.25;             ///< theta (thesis: 0.25); allowed (0, 100]
  int max_successors = 5;                ///< successors proposed from a known node; allowed [1, 8]
  int max_representatives_per_node = 8;  ///< per node and particle, oldest dropped; allowed [1, 16]
  /// Literal "no return to the previous node": also drop the node visited just before the current one
  /// from the successor candidates. Off by default: the successor model never proposes a node that only
  /// preceded the current one anyway, and one that also followed it earlier is a forward move (see docs).
  bool forbid_return_to_previous = false;
  std::uint64_t seed = 1;  ///< of the filter's std::mt19937_64
  LikelihoodModel likelihood = LikelihoodModel::Absolute;
  double relative_slope = 3.0;         ///< logistic slope per z unit; allowed (0, 100]
  double relative_offset = 2.5;        ///< z at which the likelihood is 1/2; allowed [-10, 10]
  double relative_sigma_floor = 0.02;  ///< smallest spread of the others' similarities; allowed (0, 1]
  /// Eq. 5.7: a new node's likelihood is eta (1 - max L), eta the normalised entropy of the known nodes'
  /// likelihoods (the thesis). Off: 1 - max L. The relative likelihood is already relative to the other
  /// places, and normalising its near-zero values makes eta collapse: one place at L = 0.035 took 0.97 of
  /// the particles (docs/topology.md, "The new node's likelihood"). Saved with the map; maps written
  /// before it existed load with it on.
  bool new_node_entropy = true;
  /// Smallest likelihood of a new node: max(eta (1 - max L), floor), the probability that a new place
  /// looks like a stored one (perceptual aliasing). 0 (the thesis): a known node at L ~ 1 leaves a new
  /// node ~1e-4 of the weight, so on look-alike rooms no particle keeps the right branch and the places
  /// after it cannot undo the wrong closure (docs/topology.md, "Look-alike rooms"). Saved with the map;
  /// maps written before it existed load with 0. Allowed [0, 1).
  double new_node_likelihood_floor = 0.0;
  /// Not part of the saved state (a loaded map has the defaults until setCandidateSelection()).
  CandidateSelectionConfig candidates;
  /// Returns "" when valid, else "<key>: <problem, allowed range>".
  std::string validate() const;
};

/// Gamma pdf with shape k and scale theta at x > 0.
double gammaPdf(double x, double shape, double scale);

/// Normalised entropy (eq. 5.6) of likelihoods after normalising them to sum 1, in [0, 1]. 1 for fewer
/// than two values or when all are zero (no information).
double normalisedEntropy(std::span<const double> likelihoods);

/// Appearance likelihood of a new node (eq. 5.7): eta * (1 - max). 1 with no known node.
double newNodeLikelihood(std::span<const double> known_likelihoods);

/// The known-node transition weights: stay[0] = weight of staying, successor[j-1] of the j-th successor,
/// for j = 1..max_successors. They are gammaPdf(j + 1) scaled so stay + all successors = 1 - new_node.
struct KnownNodeTransition {
  double stay = 0.0;
  std::vector<double> successor;
  double new_node = 0.0;  ///< the fixed part; missing successors add their weight to it
};
KnownNodeTransition knownNodeTransition(const TopologyFilterConfig& config);

/// One distinct topology held by some particles.
struct TopologyHypothesis {
  std::vector<int> assignment;  ///< node of each observation, nodes numbered in order of creation
  double probability = 0.0;     ///< share of particles holding exactly this assignment
  int node_count = 0;
  int current_node = -1;      ///< assignment.back()
  int first_difference = -1;  ///< first observation where it differs from the best (-1: it is it)
};

/// Where the robot is: "the node first seen at observation `founding_observation`".
struct LocationHypothesis {
  int founding_observation = -1;  ///< first observation of the current node in those particles
  int node_in_best = -1;          ///< that node's id in the best topology, -1 if it has none there
  double probability = 0.0;       ///< share of particles whose current node has this founding observation
};

struct TopologyEstimate {
  int observations = 0;
  TopologyHypothesis best;                       ///< most particles agree on it (ties: first particle)
  std::vector<TopologyHypothesis> alternatives;  ///< the next most probable topologies, descending
  int current_node = -1;                         ///< in the best topology
  double current_node_probability = 0.0;         ///< share of particles at the same node (founding obs)
  std::vector<LocationHypothesis> locations;     ///< all current-node hypotheses, descending
  double effective_sample_size = 0.0;            ///< of the last step's weights (1 / sum w^2, normalised)
  int distinct_topologies = 0;
};

/// Sizes of the shared structures, for tests and benchmarks (counts reachable objects: O(size)).
struct TopologyMemoryStats {
  std::size_t distinct_states = 0;
  std::size_t history_records = 0;  ///< live assignment records (shared by all particles)
  std::size_t trie_nodes = 0;       ///< live node-table trie nodes (shared)
  std::size_t stored_fingerprints = 0;
  std::size_t candidate_index_bytes = 0;  ///< heap held by the candidate index (0 until it is built)
};

/// The filter's state between two steps, frozen (TopologyParticleFilter::freeze()). The particles and
/// stored fingerprints are shared, immutable data, so taking it costs pointer copies (O(particles +
/// observations)), while encoding it, which grows with the map, can be done later on another thread as
/// the filter goes on: the pipeline takes it on the topology thread and encodes it on the map writer's.
/// Thread-safety: saveState() from any one thread at a time; the filter may step meanwhile.
class FrozenTopologyState {
 public:
  /// The bytes TopologyParticleFilter::saveState wrote at the moment freeze() was called.
  void saveState(std::ostream& out) const;
  /// The bytes saveState writes, appended to `out` (a map save builds its file in one buffer).
  void appendState(std::string& out) const;
  int observationCount() const { return observation_count_; }

 private:
  friend class TopologyParticleFilter;
  TopologyFilterConfig config_;
  std::mt19937_64 rng_;
  int observation_count_ = 0;
  double last_ess_ = 0.0;
  std::int64_t degenerate_steps_ = 0;
  std::vector<std::shared_ptr<const Fingerprint>> fingerprints_;
  std::vector<std::shared_ptr<const topology_detail::TopologyState>> particles_;
};

class TopologyParticleFilter {
 public:
  /// Throws std::invalid_argument with config.validate()'s message when invalid.
  TopologyParticleFilter(const TopologyFilterConfig& config, const SimilarityMeasure& similarity);
  ~TopologyParticleFilter();
  TopologyParticleFilter(const TopologyParticleFilter&) = delete;
  TopologyParticleFilter& operator=(const TopologyParticleFilter&) = delete;

  /// Starts the step for a new representative. Throws std::logic_error while a step is in progress and
  /// std::invalid_argument for a null fingerprint or more evidence values than observations.
  /// `evidence` (optional): per earlier observation, a likelihood in [0, 1] from outside the
  /// representatives (PlaceSequenceEvidence); a stored representative's likelihood is then the larger of
  /// its own and its observation's evidence. Empty: the representatives alone (the thesis).
  /// `samples` (optional, LikelihoodModel::Relative only): other frames of the same place. Each is
  /// compared with the stored representatives like the representative and turned into relative
  /// likelihoods the same way; a stored representative's likelihood is then the geometric mean of the
  /// representative's and the larger of it and the best sample's (docs/topology.md, "Place samples").
  /// Null samples are ignored.
  void beginStep(std::shared_ptr<const Fingerprint> representative, std::span<const double> evidence = {},
                 std::span<const std::shared_ptr<const Fingerprint>> samples = {});
  /// Runs at most `budget` work items of the current step (>= 1; one item = one similarity evaluation,
  /// one distinct topology scanned or aggregated, or one particle proposed/weighted/updated). Returns
  /// true when the step is complete (also when no step is in progress). Sliced and whole runs of a step
  /// give identical results.
  bool advance(std::size_t budget);
  /// beginStep + advance until done.
  void step(std::shared_ptr<const Fingerprint> representative, std::span<const double> evidence = {},
            std::span<const std::shared_ptr<const Fingerprint>> samples = {});
  bool stepInProgress() const { return phase_ != Phase::Idle; }

  const TopologyFilterConfig& config() const { return config_; }
  int observationCount() const { return observation_count_; }  ///< completed steps
  /// Summary of the current particles (call between steps). O(M log M + history): the best topology's
  /// assignment is copied out whole, but only the history records since the last call's best topology
  /// and, per alternative, those since it left the best are walked.
  TopologyEstimate estimate(int alternatives = 4) const;
  /// Assignment sequence of particle i (for tests).
  std::vector<int> particleAssignment(int i) const;
  double lastEffectiveSampleSize() const { return last_ess_; }
  /// Steps whose weights were all zero (resampled uniformly).
  std::int64_t degenerateSteps() const { return degenerate_steps_; }
  TopologyMemoryStats memoryStats() const;
  /// Replaces config().candidates (between steps; throws std::logic_error during a step and
  /// std::invalid_argument when invalid). The index is rebuilt from the stored representatives when
  /// next needed.
  void setCandidateSelection(const CandidateSelectionConfig& candidates);
  /// A copy that shares this filter's immutable state (particles, stored representatives): O(particles +
  /// observations) pointer copies. For benchmarks and tests that try a step two ways from one state.
  /// Neither copy may step while the other does (they share memo fields). Throws std::logic_error during
  /// a step.
  std::unique_ptr<TopologyParticleFilter> fork() const { return fork(similarity_); }
  /// The same, comparing through `similarity` from now on (it must outlive the copy).
  std::unique_ptr<TopologyParticleFilter> fork(const SimilarityMeasure& similarity) const;
  /// Steps that compared through the candidate index instead of exhaustively.
  std::int64_t indexedSteps() const { return indexed_steps_; }
  /// Exact similarity evaluations of the last step.
  std::size_t lastStepComparisons() const { return compared_list_.size(); }
  /// Representatives still referenced by some particle (the ones step 1 compares against).
  std::shared_ptr<const Fingerprint> storedRepresentative(int observation) const;

  /// Binary state (config, RNG, fingerprints, history, particles). Throws std::logic_error during a
  /// step. Little-endian; framed, versioned and checksummed by MapStore. Same as freeze().saveState(out).
  void saveState(std::ostream& out) const;
  /// The state as it is now, for saveState() later (see FrozenTopologyState). Throws std::logic_error
  /// during a step.
  FrozenTopologyState freeze() const;
  /// Inverse of saveState; throws std::runtime_error on malformed data.
  static std::unique_ptr<TopologyParticleFilter> loadState(std::istream& in,
                                                           const SimilarityMeasure& similarity);
  /// loadState of bytes in memory (no copy of them: a map load reads the file's payload in place).
  static std::unique_ptr<TopologyParticleFilter> loadState(std::string_view data,
                                                           const SimilarityMeasure& similarity);

 private:
  enum class Phase : std::uint8_t { Idle, Collect, Propose, Similarity, Aggregate, Resample, Update };
  using StatePtr = std::shared_ptr<const topology_detail::TopologyState>;

  /// Work items one advance() call may still run: each phase takes one per item and stops (returns
  /// false, to resume at cursor_) when none is left.
  struct WorkBudget {
    std::size_t used = 0;
    std::size_t limit = 0;
    bool take() { return used++ < limit; }
  };

  double uniform01();
  void finishStep();
  // The phases of a step, in order (each returns false when the budget ran out before it finished).
  /// Which stored representatives some particle still refers to (needed_list_); the others are forgotten.
  bool collectStored(WorkBudget& work);
  /// Step 1: each particle draws its next node from the transition model (proposal_).
  bool proposeNodes(WorkBudget& work);
  /// Step 2: the new representative (and samples) against the stored ones, into likelihoods.
  bool compareWithStored(WorkBudget& work);
  /// Per distinct topology: its best known-node likelihood and its new node's likelihood (group_stats_).
  bool aggregatePerTopology(WorkBudget& work);
  /// Steps 3 and 4: weigh the proposals, then systematic resampling (chosen_).
  bool resample(WorkBudget& work);
  /// Step 3: each particle's weight, the appearance likelihood of its proposal (weight_).
  void weighProposals();
  /// Step 5: the chosen particles' states extended by their proposals (next_particles_), then finishStep.
  bool updateMap(WorkBudget& work);
  /// LikelihoodModel::Relative: turns this step's similarities into relative likelihoods, in place.
  void relativeLikelihoods();
  /// After Collect: which stored representatives step 1 compares exactly (compared_list_).
  void selectComparisons();
  /// After the exact comparisons of an indexed step: the background for the others.
  void fillBackground();
  /// Relative likelihoods with the place's samples (see beginStep), in place in similarity_of_.
  void relativeLikelihoodsWithSamples();

  TopologyFilterConfig config_;
  const SimilarityMeasure& similarity_;
  std::mt19937_64 rng_;
  KnownNodeTransition transition_;

  int observation_count_ = 0;
  std::uint64_t stamp_ = 0;  ///< memo key of the trie aggregates, one per step
  std::vector<std::shared_ptr<const Fingerprint>> fingerprints_;  ///< by observation; null = dropped
  std::vector<StatePtr> particles_;
  double last_ess_ = 0.0;
  std::int64_t degenerate_steps_ = 0;

  // Step in progress.
  Phase phase_ = Phase::Idle;
  std::size_t cursor_ = 0;
  std::shared_ptr<const Fingerprint> pending_;
  std::vector<std::shared_ptr<const Fingerprint>> pending_samples_;  ///< the place's other frames
  std::vector<double> sample_similarity_;          ///< raw, sample-major: [k * observations + o]
  std::vector<double> best_sample_likelihood_;     ///< per observation, the best sample's relative likelihood
  std::vector<double> representative_similarity_;  ///< the representative's raw similarities, set aside
  std::vector<StatePtr> groups_;        ///< distinct parent states, in order of first particle
  std::vector<std::int32_t> group_of_;  ///< per particle
  std::vector<unsigned char> needed_;   ///< per observation: referenced by some group
  std::vector<std::int32_t> needed_list_;
  std::vector<double> similarity_of_;  ///< per observation, this step
  std::vector<double> evidence_;       ///< per observation, this step (beginStep's; may be shorter)
  std::vector<std::int32_t> compared_list_;  ///< compared exactly this step (all of needed_list_ unless indexed)
  bool indexed_step_ = false;
  double background_extra_sq_ = 0.0;  ///< sum of squared deviations the background values stand for
  std::int64_t indexed_steps_ = 0;
  std::unique_ptr<PlaceCandidateIndex> index_;  ///< holds the stored representatives once built
  /// Per observation, while index_ exists: PlaceCandidateIndex::supports() of its fingerprint (asked once,
  /// not per step: reading every stored fingerprint each step is a cache miss per place).
  std::vector<unsigned char> indexable_;
  struct GroupStats {
    double max = 0.0;
    double new_likelihood = 1.0;
  };
  std::vector<GroupStats> group_stats_;
  std::vector<std::int32_t> proposal_;  ///< per particle: node (== node_count for a new node)
  std::vector<double> weight_;
  std::vector<std::int32_t> chosen_;  ///< resampled particle indices
  std::vector<StatePtr> next_particles_;
  std::unordered_map<std::uint64_t, std::int32_t> child_index_;  ///< (group, node) -> child
  std::vector<StatePtr> children_;

  // estimate()'s memo (mutable: a cache, the filter is single-threaded): the last best topology, its
  // history record and node per observation. The next best shares all but its last records with it.
  mutable StatePtr estimate_state_;  ///< keeps the records below alive (so no address is reused)
  mutable std::vector<const topology_detail::HistoryRecord*> estimate_records_;
  mutable std::vector<int> estimate_assignment_;
};

}  // namespace toposlam
