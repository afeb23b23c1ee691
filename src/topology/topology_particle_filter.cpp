// TopologyParticleFilter: the step machine (collect, similarity, aggregate, propose, resample, update),
// the estimate, and state (de)serialisation. See the header and docs/topology.md.
#include "toposlam/topology/topology_particle_filter.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "binary_io.hpp"
#include "topology_state.hpp"

namespace toposlam {

using topology_detail::BinaryReader;
using topology_detail::BinaryWriter;
using topology_detail::HistoryRecord;
using topology_detail::kTrieBits;
using topology_detail::kTrieFanout;
using topology_detail::NodeEntry;
using topology_detail::TopologyState;
using topology_detail::TrieBranch;
using topology_detail::TrieLeaf;
using topology_detail::TrieNode;

namespace {

std::size_t idx(std::int64_t i) { return static_cast<std::size_t>(i); }

/// eta from S1 = sum L, S2 = sum L log L over n known nodes: sum p log p = S2 / S1 - log S1.
double entropyFromSums(double sum, double sum_l_log_l, int n) {
  if (n <= 1 || !(sum > 0.0)) return 1.0;
  const double eta = -(sum_l_log_l / sum - std::log(sum)) / std::log(static_cast<double>(n));
  return std::clamp(eta, 0.0, 1.0);
}

double lLogL(double l) { return l > 0.0 ? l * std::log(l) : 0.0; }

/// lLogL that remembers its last argument: on an indexed step most nodes have the one background
/// likelihood, so the logarithm is taken once for all of them (same value, bit for bit).
struct LLogLMemo {
  double l = std::numeric_limits<double>::quiet_NaN();
  double l_log_l = 0.0;
  double operator()(double value) {
    if (value != l) {
      l = value;
      l_log_l = lLogL(value);
    }
    return l_log_l;
  }
};

double entryLikelihood(const NodeEntry& entry, const std::vector<double>& similarity) {
  double best = 0.0;
  for (int r = 0; r < entry.representative_count; ++r) {
    best = std::max(best, similarity[idx(entry.representatives[idx(r)])]);
  }
  return best;
}

/// Marks the observations referenced below `node` (each shared trie node once per stamp).
void markReferenced(const TrieNode* node, int level, std::uint64_t stamp,
                    std::vector<unsigned char>& needed) {
  if (!node || node->visit_stamp == stamp) return;
  node->visit_stamp = stamp;
  if (level == 0) {
    for (const NodeEntry& entry : static_cast<const TrieLeaf*>(node)->entries) {
      for (int r = 0; r < entry.representative_count; ++r) needed[idx(entry.representatives[idx(r)])] = 1;
    }
    return;
  }
  for (const auto& child : static_cast<const TrieBranch*>(node)->children) {
    markReferenced(child.get(), level - 1, stamp, needed);
  }
}

/// Sums of node likelihoods below `node`, memoised per stamp (shared subtrees are summed once).
void aggregate(const TrieNode* node, int level, std::uint64_t stamp, const std::vector<double>& similarity,
               LLogLMemo& l_log_l) {
  if (node->memo_stamp == stamp) return;
  double sum = 0.0, sum_l_log_l = 0.0, max = 0.0;
  if (level == 0) {
    for (const NodeEntry& entry : static_cast<const TrieLeaf*>(node)->entries) {
      if (entry.first_observation < 0) continue;
      const double l = entryLikelihood(entry, similarity);
      sum += l;
      sum_l_log_l += l_log_l(l);
      max = std::max(max, l);
    }
  } else {
    for (const auto& child : static_cast<const TrieBranch*>(node)->children) {
      if (!child) continue;
      aggregate(child.get(), level - 1, stamp, similarity, l_log_l);
      sum += child->memo_sum;
      sum_l_log_l += child->memo_sum_l_log_l;
      max = std::max(max, child->memo_max);
    }
  }
  node->memo_sum = sum;
  node->memo_sum_l_log_l = sum_l_log_l;
  node->memo_max = max;
  node->memo_stamp = stamp;
}

std::vector<int> assignmentOf(const TopologyState& state) {
  std::vector<int> out;
  for (const HistoryRecord* r = state.record.get(); r; r = r->parent.get()) out.push_back(r->node);
  std::reverse(out.begin(), out.end());
  return out;
}

void countTrieNodes(const TrieNode* node, int level, std::unordered_set<const TrieNode*>& seen) {
  if (!node || !seen.insert(node).second || level == 0) return;
  for (const auto& child : static_cast<const TrieBranch*>(node)->children)
    countTrieNodes(child.get(), level - 1, seen);
}

}  // namespace

std::string TopologyFilterConfig::validate() const {
  if (particles < 1 || particles > 1000000) return "particles: must be in [1, 1000000]";
  if (!(alpha > 0.0 && alpha <= 1e6)) return "alpha: must be in (0, 1e6]";
  if (!(new_node_probability > 0.0 && new_node_probability < 1.0))
    return "new_node_probability: must be in (0, 1)";
  if (!(gamma_shape > 0.0 && gamma_shape <= 1000.0)) return "gamma_shape: must be in (0, 1000]";
  if (!(gamma_scale > 0.0 && gamma_scale <= 100.0)) return "gamma_scale: must be in (0, 100]";
  if (max_successors < 1 || max_successors > kTopologyMaxSuccessors)
    return "max_successors: must be in [1, 8]";
  if (max_representatives_per_node < 1 || max_representatives_per_node > kTopologyMaxRepresentatives) {
    return "max_representatives_per_node: must be in [1, 16]";
  }
  if (likelihood != LikelihoodModel::Absolute && likelihood != LikelihoodModel::Relative)
    return "likelihood: must be absolute or relative";
  if (!(relative_slope > 0.0 && relative_slope <= 100.0)) return "relative_slope: must be in (0, 100]";
  if (!(relative_offset >= -10.0 && relative_offset <= 10.0)) return "relative_offset: must be in [-10, 10]";
  if (!(relative_sigma_floor > 0.0 && relative_sigma_floor <= 1.0))
    return "relative_sigma_floor: must be in (0, 1]";
  if (!(new_node_likelihood_floor >= 0.0 && new_node_likelihood_floor < 1.0))
    return "new_node_likelihood_floor: must be in [0, 1)";
  if (const std::string problem = candidates.validate(); !problem.empty()) return "candidates." + problem;
  return "";
}

std::string CandidateSelectionConfig::validate() const {
  if (exhaustive_up_to < 0 || exhaustive_up_to > 1000000000) return "exhaustive_up_to: must be in [0, 1000000000]";
  if (candidates < 1 || candidates > 100000) return "candidates: must be in [1, 100000]";
  if (background_samples < 0 || background_samples > 100000) return "background_samples: must be in [0, 100000]";
  if (const std::string problem = index.validate(); !problem.empty()) return "index." + problem;
  return "";
}

const char* toString(LikelihoodModel model) {
  return model == LikelihoodModel::Relative ? "relative" : "absolute";
}

LikelihoodModel parseLikelihoodModel(const std::string& name) {
  if (name == "absolute") return LikelihoodModel::Absolute;
  if (name == "relative") return LikelihoodModel::Relative;
  throw std::invalid_argument("likelihood model '" + name + "': expected absolute or relative");
}

double relativeLikelihood(double similarity, double others_sum, double others_sum_sq, int others_count,
                          double slope, double offset, double sigma_floor) {
  double z = 0.0;
  if (others_count > 0) {
    const double n = static_cast<double>(others_count);
    const double mean = others_sum / n;
    const double variance = std::max(0.0, others_sum_sq / n - mean * mean);
    z = (similarity - mean) / std::max(std::sqrt(variance), sigma_floor);
  }
  return 1.0 / (1.0 + std::exp(-slope * (z - offset)));
}

double gammaPdf(double x, double shape, double scale) {
  if (!(x > 0.0)) return 0.0;
  return std::exp((shape - 1.0) * std::log(x) - x / scale - std::lgamma(shape) - shape * std::log(scale));
}

double normalisedEntropy(std::span<const double> likelihoods) {
  double sum = 0.0, sum_l_log_l = 0.0;
  for (double l : likelihoods) {
    sum += l;
    sum_l_log_l += lLogL(l);
  }
  return entropyFromSums(sum, sum_l_log_l, static_cast<int>(likelihoods.size()));
}

double newNodeLikelihood(std::span<const double> known_likelihoods) {
  if (known_likelihoods.empty()) return 1.0;
  const double max = *std::max_element(known_likelihoods.begin(), known_likelihoods.end());
  return normalisedEntropy(known_likelihoods) * (1.0 - max);
}

KnownNodeTransition knownNodeTransition(const TopologyFilterConfig& config) {
  KnownNodeTransition t;
  std::array<double, kTopologyMaxSuccessors + 1> raw{};
  double total = 0.0;
  for (int j = 0; j <= config.max_successors; ++j) {
    raw[idx(j)] = gammaPdf(j + 1.0, config.gamma_shape, config.gamma_scale);
    total += raw[idx(j)];
  }
  const double scale = (1.0 - config.new_node_probability) / total;
  t.stay = raw[0] * scale;
  for (int j = 1; j <= config.max_successors; ++j) t.successor.push_back(raw[idx(j)] * scale);
  t.new_node = config.new_node_probability;
  return t;
}

TopologyParticleFilter::TopologyParticleFilter(const TopologyFilterConfig& config,
                                               const SimilarityMeasure& similarity)
    : config_(config), similarity_(similarity) {
  if (const std::string problem = config_.validate(); !problem.empty()) throw std::invalid_argument(problem);
  rng_.seed(config_.seed);
  transition_ = knownNodeTransition(config_);
  particles_.assign(idx(config_.particles), std::make_shared<const TopologyState>());
}

TopologyParticleFilter::~TopologyParticleFilter() = default;

double TopologyParticleFilter::uniform01() {
  // 53 random bits -> [0, 1), identical on every platform (std distributions are not specified).
  return static_cast<double>(rng_() >> 11) * 0x1.0p-53;
}

void TopologyParticleFilter::relativeLikelihoods() {
  // Leave-one-out: each stored representative against the others this step compares with. Sums in
  // observation order, so the result does not depend on how the step was sliced.
  double sum = 0.0, sum_sq = 0.0;
  for (const std::int32_t o : needed_list_) {
    const double s = similarity_of_[idx(o)];
    sum += s;
    sum_sq += s * s;
  }
  sum_sq += background_extra_sq_;  // 0 unless indexed: the spread the background values stand for
  const int others = static_cast<int>(needed_list_.size()) - 1;
  // On an indexed step most values are the background's one: the same input gives the same likelihood,
  // so it is computed once for them (an exp per stored representative otherwise).
  double last_in = std::numeric_limits<double>::quiet_NaN(), last_out = 0.0;
  for (const std::int32_t o : needed_list_) {
    double& s = similarity_of_[idx(o)];
    if (s != last_in) {
      last_in = s;
      last_out = relativeLikelihood(s, sum - s, sum_sq - s * s, others, config_.relative_slope,
                                    config_.relative_offset, config_.relative_sigma_floor);
    }
    s = last_out;
  }
}

void TopologyParticleFilter::beginStep(std::shared_ptr<const Fingerprint> representative,
                                       std::span<const double> evidence,
                                       std::span<const std::shared_ptr<const Fingerprint>> samples) {
  if (phase_ != Phase::Idle) throw std::logic_error("TopologyParticleFilter: a step is already in progress");
  if (!representative) throw std::invalid_argument("TopologyParticleFilter: null representative");
  if (evidence.size() > idx(observation_count_))
    throw std::invalid_argument("TopologyParticleFilter: evidence for " + std::to_string(evidence.size()) +
                                " observations, only " + std::to_string(observation_count_) + " made");
  evidence_.assign(evidence.begin(), evidence.end());
  for (double& e : evidence_) e = std::isfinite(e) ? std::clamp(e, 0.0, 1.0) : 0.0;
  if (observation_count_ == std::numeric_limits<std::int32_t>::max())
    throw std::length_error("too many observations");
  pending_ = std::move(representative);
  pending_samples_.clear();
  if (config_.likelihood == LikelihoodModel::Relative)
    for (const auto& sample : samples)
      if (sample) pending_samples_.push_back(sample);
  sample_similarity_.assign(pending_samples_.size() * idx(observation_count_), 0.0);
  ++stamp_;
  const std::size_t m = particles_.size();
  groups_.clear();
  group_of_.assign(m, 0);
  std::unordered_map<const TopologyState*, std::int32_t> group_index;
  for (std::size_t i = 0; i < m; ++i) {
    auto [it, inserted] = group_index.emplace(particles_[i].get(), static_cast<std::int32_t>(groups_.size()));
    if (inserted) groups_.push_back(particles_[i]);
    group_of_[i] = it->second;
  }
  needed_.assign(idx(observation_count_), 0);
  needed_list_.clear();
  similarity_of_.assign(idx(observation_count_), 0.0);
  group_stats_.assign(groups_.size(), GroupStats{});
  proposal_.assign(m, 0);
  weight_.assign(m, 0.0);
  chosen_.assign(m, 0);
  next_particles_.assign(m, nullptr);
  child_index_.clear();
  phase_ = Phase::Collect;
  cursor_ = 0;
}

bool TopologyParticleFilter::advance(std::size_t budget) {
  if (budget == 0) throw std::invalid_argument("TopologyParticleFilter::advance: budget must be >= 1");
  std::size_t used = 0;
  const std::size_t m = particles_.size();
  LLogLMemo l_log_l_memo;
  while (phase_ != Phase::Idle) {
    switch (phase_) {
      case Phase::Collect:
        for (; cursor_ < groups_.size(); ++cursor_) {
          if (used++ >= budget) return false;
          const TopologyState& g = *groups_[cursor_];
          markReferenced(g.nodes.root().get(), g.nodes.levels(), stamp_, needed_);
        }
        for (std::size_t o = 0; o < needed_.size(); ++o) {
          if (needed_[o]) {
            needed_list_.push_back(static_cast<std::int32_t>(o));
          } else if (fingerprints_[o]) {
            if (index_) index_->remove(static_cast<int>(o), *fingerprints_[o]);
            fingerprints_[o].reset();  // no particle refers to it any more: forget it
          }
        }
        phase_ = Phase::Propose;
        cursor_ = 0;
        break;
      case Phase::Similarity: {
        // The representative's comparisons, then each sample's: one work item each.
        const std::size_t compared = compared_list_.size();
        for (; cursor_ < compared * (1 + pending_samples_.size()); ++cursor_) {
          if (used++ >= budget) return false;
          const std::size_t pass = cursor_ / compared;
          const auto o = idx(compared_list_[cursor_ % compared]);
          const Fingerprint& query = pass == 0 ? *pending_ : *pending_samples_[pass - 1];
          const double s = similarity_.similarity(*fingerprints_[o], query);
          const double value = std::isfinite(s) ? std::clamp(s, 0.0, 1.0) : 0.0;
          if (pass == 0) {
            similarity_of_[o] = value;
          } else {
            sample_similarity_[(pass - 1) * similarity_of_.size() + o] = value;
          }
        }
        if (indexed_step_) fillBackground();
        if (config_.likelihood == LikelihoodModel::Relative) {
          if (pending_samples_.empty()) {
            relativeLikelihoods();
          } else {
            relativeLikelihoodsWithSamples();
          }
        }
        if (!evidence_.empty())
          for (const std::int32_t o : needed_list_)
            if (idx(o) < evidence_.size()) similarity_of_[idx(o)] = std::max(similarity_of_[idx(o)], evidence_[idx(o)]);
        phase_ = Phase::Aggregate;
        cursor_ = 0;
        break;
      }
      case Phase::Aggregate:
        for (; cursor_ < groups_.size(); ++cursor_) {
          if (used++ >= budget) return false;
          const TopologyState& g = *groups_[cursor_];
          GroupStats& stats = group_stats_[cursor_];
          if (g.nodeCount() == 0) continue;  // first observation: nothing known
          aggregate(g.nodes.root().get(), g.nodes.levels(), stamp_, similarity_of_, l_log_l_memo);
          const TrieNode& root = *g.nodes.root();
          stats.max = root.memo_max;
          const double eta = config_.new_node_entropy
                                 ? entropyFromSums(root.memo_sum, root.memo_sum_l_log_l, g.nodeCount())
                                 : 1.0;
          stats.new_likelihood = std::max(eta * (1.0 - stats.max), config_.new_node_likelihood_floor);
        }
        phase_ = Phase::Resample;
        cursor_ = 0;
        break;
      case Phase::Propose:
        for (; cursor_ < m; ++cursor_) {
          if (used++ >= budget) return false;
          const auto g = idx(group_of_[cursor_]);
          const TopologyState& state = *groups_[g];
          const int n = state.nodeCount();
          std::int32_t next = n;  // new node unless chosen otherwise
          if (n > 0) {
            const int current = state.currentNode();
            const NodeEntry& entry = state.nodes.get(current);
            if (entry.successor_count == 0) {
              // No adjacency information (never left this node): eq. 5.8.
              const double u = uniform01() * (n + config_.alpha);
              if (u < n) next = std::min(static_cast<std::int32_t>(u), static_cast<std::int32_t>(n - 1));
            } else {
              const double u = uniform01();
              double cumulative = transition_.stay;
              if (u < cumulative) {
                next = current;
              } else {
                const int previous = state.previousNode();
                std::size_t rank = 0;
                for (int s = 0; s < entry.successor_count && rank < transition_.successor.size(); ++s) {
                  const std::int32_t candidate = entry.successors[idx(s)];
                  if (config_.forbid_return_to_previous && candidate == previous) continue;
                  cumulative += transition_.successor[rank++];
                  if (u < cumulative) {
                    next = candidate;
                    break;
                  }
                }
              }
            }
          }
          proposal_[cursor_] = next;
        }
        selectComparisons();
        phase_ = Phase::Similarity;
        cursor_ = 0;
        break;
      case Phase::Resample: {
        if (used++ >= budget) return false;
        for (std::size_t i = 0; i < m; ++i) {
          const auto g = idx(group_of_[i]);
          const TopologyState& state = *groups_[g];
          weight_[i] = proposal_[i] == state.nodeCount() ? group_stats_[g].new_likelihood
                                                         : entryLikelihood(state.nodes.get(proposal_[i]), similarity_of_);
        }
        double total = 0.0, total_sq = 0.0;
        for (double w : weight_) {
          total += w;
          total_sq += w * w;
        }
        if (!(total > 0.0) || !std::isfinite(total)) {
          std::fill(weight_.begin(), weight_.end(), 1.0);
          total = static_cast<double>(m);
          total_sq = total;
          ++degenerate_steps_;
        }
        last_ess_ = total * total / total_sq;
        // Systematic resampling: one uniform offset, M evenly spaced pointers.
        const double spacing = total / static_cast<double>(m);
        double pointer = uniform01() * spacing;
        std::size_t i = 0;
        double cumulative = weight_[0];
        for (std::size_t j = 0; j < m; ++j) {
          while (cumulative <= pointer && i + 1 < m) cumulative += weight_[++i];
          chosen_[j] = static_cast<std::int32_t>(i);
          pointer += spacing;
        }
        phase_ = Phase::Update;
        cursor_ = 0;
        break;
      }
      case Phase::Update:
        for (; cursor_ < m; ++cursor_) {
          if (used++ >= budget) return false;
          const auto source = idx(chosen_[cursor_]);
          const auto g = static_cast<std::uint64_t>(group_of_[source]);
          const auto node = static_cast<std::uint64_t>(proposal_[source]);
          const std::uint64_t key = (g << 32) | node;
          auto [it, inserted] = child_index_.emplace(key, static_cast<std::int32_t>(children_.size()));
          if (inserted) {
            children_.push_back(topology_detail::extendState(*groups_[idx(g)], observation_count_,
                                                             proposal_[source], config_));
          }
          next_particles_[cursor_] = children_[idx(it->second)];
        }
        finishStep();
        break;
      case Phase::Idle:
        break;
    }
  }
  return true;
}

void TopologyParticleFilter::relativeLikelihoodsWithSamples() {
  // Each sample's similarities become relative likelihoods exactly as the representative's do (an
  // indexed step fills the uncompared ones with that sample's own background); a stored
  // representative keeps the best of them. Its likelihood is then sqrt(l_rep * max(l_rep, l_best)):
  // a sample can raise it, never lower it, and a single sample matching alone cannot reach 1.
  const std::size_t n = similarity_of_.size();
  representative_similarity_ = similarity_of_;
  best_sample_likelihood_.assign(n, 0.0);
  for (std::size_t k = 0; k < pending_samples_.size(); ++k) {
    for (const std::int32_t o : compared_list_) similarity_of_[idx(o)] = sample_similarity_[k * n + idx(o)];
    if (indexed_step_) fillBackground();
    relativeLikelihoods();
    for (const std::int32_t o : needed_list_)
      best_sample_likelihood_[idx(o)] = std::max(best_sample_likelihood_[idx(o)], similarity_of_[idx(o)]);
  }
  similarity_of_ = representative_similarity_;
  if (indexed_step_) fillBackground();
  relativeLikelihoods();
  for (const std::int32_t o : needed_list_) {
    double& l = similarity_of_[idx(o)];
    l = std::sqrt(l * std::max(l, best_sample_likelihood_[idx(o)]));
  }
}

void TopologyParticleFilter::selectComparisons() {
  // needed_ marks: 1 = stored, 2 = compared (candidate or not indexable), 3 = compared (background sample).
  indexed_step_ = false;
  background_extra_sq_ = 0.0;
  const CandidateSelectionConfig& c = config_.candidates;
  if (needed_list_.size() <= idx(c.exhaustive_up_to) || !PlaceCandidateIndex::supports(*pending_)) {
    compared_list_ = needed_list_;
    return;
  }
  if (!index_) {
    index_ = std::make_unique<PlaceCandidateIndex>(c.index);
    indexable_.assign(fingerprints_.size(), 0);
    for (std::size_t o = 0; o < fingerprints_.size(); ++o) {
      if (!fingerprints_[o]) continue;
      index_->add(static_cast<int>(o), *fingerprints_[o]);
      indexable_[o] = PlaceCandidateIndex::supports(*fingerprints_[o]) ? 1 : 0;
    }
  }
  indexed_step_ = true;
  ++indexed_steps_;
  for (const int o : index_->candidates(*pending_, c.candidates)) needed_[idx(o)] = 2;
  // The known nodes the particles propose: their likelihoods are the particles' weights, so they are
  // compared exactly whatever the index says (the proposals do not depend on the similarities).
  for (std::size_t i = 0; i < proposal_.size(); ++i) {
    const TopologyState& state = *groups_[idx(group_of_[i])];
    if (proposal_[i] >= state.nodeCount()) continue;
    const NodeEntry& entry = state.nodes.get(proposal_[i]);
    for (int r = 0; r < entry.representative_count; ++r) needed_[idx(entry.representatives[idx(r)])] = 2;
  }
  std::size_t rest = 0;
  for (const std::int32_t o : needed_list_) {
    if (needed_[idx(o)] != 1) continue;
    if (indexable_[idx(o)]) {
      ++rest;
    } else {
      needed_[idx(o)] = 2;  // the index cannot hold it: always compared
    }
  }
  const std::size_t samples = std::min(rest, idx(c.background_samples));
  std::size_t seen = 0, next_sample = 0, taken = 0;
  for (const std::int32_t o : needed_list_) {
    if (needed_[idx(o)] != 1) continue;
    // Evenly spread: the i-th sample is the (i * rest / samples)-th of the rest, in observation order.
    if (taken < samples && seen == next_sample) {
      needed_[idx(o)] = 3;
      ++taken;
      next_sample = taken * rest / samples;
    }
    ++seen;
  }
  compared_list_.clear();
  for (const std::int32_t o : needed_list_)
    if (needed_[idx(o)] >= 2) compared_list_.push_back(o);
}

void TopologyParticleFilter::fillBackground() {
  double sum = 0.0, sum_sq = 0.0;
  std::size_t samples = 0, filled = 0;
  for (const std::int32_t o : compared_list_) {
    if (needed_[idx(o)] != 3) continue;
    const double s = similarity_of_[idx(o)];
    sum += s;
    sum_sq += s * s;
    ++samples;
  }
  const double mean = samples > 0 ? sum / static_cast<double>(samples) : 0.0;
  const double variance = samples > 0 ? std::max(0.0, sum_sq / static_cast<double>(samples) - mean * mean) : 0.0;
  for (const std::int32_t o : needed_list_) {
    if (needed_[idx(o)] != 1) continue;
    similarity_of_[idx(o)] = mean;
    ++filled;
  }
  background_extra_sq_ = static_cast<double>(filled) * variance;
}

std::unique_ptr<TopologyParticleFilter> TopologyParticleFilter::fork(const SimilarityMeasure& similarity) const {
  if (phase_ != Phase::Idle) throw std::logic_error("TopologyParticleFilter::fork: a step is in progress");
  auto copy = std::make_unique<TopologyParticleFilter>(config_, similarity);
  copy->rng_ = rng_;
  copy->observation_count_ = observation_count_;
  // Memo stamps the original will never reach: the copy's steps cannot pass for the original's.
  copy->stamp_ = stamp_ + (std::uint64_t{1} << 62);
  copy->fingerprints_ = fingerprints_;
  copy->particles_ = particles_;
  copy->last_ess_ = last_ess_;
  copy->degenerate_steps_ = degenerate_steps_;
  return copy;
}

void TopologyParticleFilter::setCandidateSelection(const CandidateSelectionConfig& candidates) {
  if (phase_ != Phase::Idle) throw std::logic_error("TopologyParticleFilter::setCandidateSelection: a step is in progress");
  if (const std::string problem = candidates.validate(); !problem.empty())
    throw std::invalid_argument("candidates." + problem);
  config_.candidates = candidates;
  index_.reset();
}

void TopologyParticleFilter::finishStep() {
  if (index_) {
    index_->add(observation_count_, *pending_);
    indexable_.push_back(PlaceCandidateIndex::supports(*pending_) ? 1 : 0);
  }
  particles_.swap(next_particles_);
  next_particles_.clear();
  children_.clear();
  child_index_.clear();
  groups_.clear();
  fingerprints_.push_back(std::move(pending_));
  pending_.reset();
  pending_samples_.clear();
  ++observation_count_;
  phase_ = Phase::Idle;
  cursor_ = 0;
}

void TopologyParticleFilter::step(std::shared_ptr<const Fingerprint> representative, std::span<const double> evidence,
                                  std::span<const std::shared_ptr<const Fingerprint>> samples) {
  beginStep(std::move(representative), evidence, samples);
  while (!advance(std::numeric_limits<std::size_t>::max())) {
  }
}

std::vector<int> TopologyParticleFilter::particleAssignment(int i) const {
  return assignmentOf(*particles_.at(idx(i)));
}

std::shared_ptr<const Fingerprint> TopologyParticleFilter::storedRepresentative(int observation) const {
  if (observation < 0 || idx(observation) >= fingerprints_.size()) return nullptr;
  return fingerprints_[idx(observation)];
}

TopologyEstimate TopologyParticleFilter::estimate(int alternatives) const {
  if (phase_ != Phase::Idle)
    throw std::logic_error("TopologyParticleFilter::estimate: a step is in progress");
  TopologyEstimate out;
  out.observations = observation_count_;
  out.effective_sample_size = last_ess_;
  const double m = static_cast<double>(particles_.size());
  // Distinct states in order of their first particle, with counts.
  std::vector<const TopologyState*> states;
  std::vector<int> counts;
  std::unordered_map<const TopologyState*, std::size_t> index;
  for (const auto& p : particles_) {
    auto [it, inserted] = index.emplace(p.get(), states.size());
    if (inserted) {
      states.push_back(p.get());
      counts.push_back(0);
    }
    ++counts[it->second];
  }
  out.distinct_topologies = static_cast<int>(states.size());
  std::vector<std::size_t> order(states.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return counts[a] > counts[b]; });

  auto describe = [&](std::size_t s) {
    TopologyHypothesis h;
    h.probability = counts[s] / m;
    h.node_count = states[s]->nodeCount();
    h.current_node = states[s]->currentNode();
    return h;
  };
  // The best topology's assignment: only the records since the one the memo (the last estimate's best)
  // shares with it are walked, usually the last step's. Walking all of them, one heap record per
  // observation, took milliseconds at 10,000 places.
  {
    std::vector<const HistoryRecord*> suffix;
    const HistoryRecord* r = states[order[0]]->record.get();
    for (; r && !(idx(r->observation) < estimate_records_.size() && estimate_records_[idx(r->observation)] == r);
         r = r->parent.get())
      suffix.push_back(r);
    const std::size_t shared = r ? idx(r->observation) + 1 : 0;
    estimate_records_.resize(shared);
    estimate_assignment_.resize(shared);
    for (auto it = suffix.rbegin(); it != suffix.rend(); ++it) {
      estimate_records_.push_back(*it);
      estimate_assignment_.push_back((*it)->node);
    }
    for (const auto& p : particles_)  // a shared_ptr of that state keeps the memo's records alive
      if (p.get() == states[order[0]]) estimate_state_ = p;
  }
  out.best = describe(order[0]);
  out.best.assignment = estimate_assignment_;
  for (std::size_t k = 1; k < order.size() && static_cast<int>(k) <= alternatives; ++k) {
    TopologyHypothesis h = describe(order[k]);
    // Its records since the last one it shares with the best topology; before that it is the best's.
    std::vector<const HistoryRecord*> suffix;
    const HistoryRecord* r = states[order[k]]->record.get();
    for (; r && !(idx(r->observation) < estimate_records_.size() && estimate_records_[idx(r->observation)] == r);
         r = r->parent.get())
      suffix.push_back(r);
    const std::size_t shared = r ? idx(r->observation) + 1 : 0;
    h.assignment.assign(estimate_assignment_.begin(), estimate_assignment_.begin() + static_cast<std::ptrdiff_t>(shared));
    for (auto it = suffix.rbegin(); it != suffix.rend(); ++it) h.assignment.push_back((*it)->node);
    for (std::size_t o = shared; o < h.assignment.size(); ++o) {
      if (h.assignment[o] != out.best.assignment[o]) {
        h.first_difference = static_cast<int>(o);
        break;
      }
    }
    out.alternatives.push_back(std::move(h));
  }
  out.current_node = out.best.current_node;
  if (observation_count_ == 0) return out;

  // Current-node hypotheses, identified by the first observation of the node.
  const TopologyState& best = *states[order[0]];
  // The best topology's node founded at observation `founder`, if any: the node it assigned that
  // observation to, when that node's first observation it is.
  const auto bestNodeOf = [&](int founder) {
    if (founder < 0 || idx(founder) >= out.best.assignment.size()) return -1;
    const int n = out.best.assignment[idx(founder)];
    return best.nodes.get(n).first_observation == founder ? n : -1;
  };
  std::vector<LocationHypothesis> locations;
  std::unordered_map<int, std::size_t> location_index;
  for (std::size_t s = 0; s < states.size(); ++s) {
    const int founder = states[s]->nodes.get(states[s]->currentNode()).first_observation;
    auto [it, inserted] = location_index.emplace(founder, locations.size());
    if (inserted) {
      LocationHypothesis l;
      l.founding_observation = founder;
      l.node_in_best = bestNodeOf(founder);
      locations.push_back(l);
    }
    locations[it->second].probability += counts[s] / m;
  }
  std::stable_sort(
      locations.begin(), locations.end(),
      [](const LocationHypothesis& a, const LocationHypothesis& b) { return a.probability > b.probability; });
  const int best_founder = best.nodes.get(best.currentNode()).first_observation;
  for (const auto& l : locations) {
    if (l.founding_observation == best_founder) out.current_node_probability = l.probability;
  }
  out.locations = std::move(locations);
  return out;
}

TopologyMemoryStats TopologyParticleFilter::memoryStats() const {
  TopologyMemoryStats stats;
  std::unordered_set<const TopologyState*> states;
  std::unordered_set<const HistoryRecord*> records;
  std::unordered_set<const TrieNode*> trie;
  for (const auto& p : particles_) {
    if (!states.insert(p.get()).second) continue;
    for (const HistoryRecord* r = p->record.get(); r && records.insert(r).second; r = r->parent.get()) {
    }
    countTrieNodes(p->nodes.root().get(), p->nodes.levels(), trie);
  }
  stats.distinct_states = states.size();
  stats.history_records = records.size();
  stats.trie_nodes = trie.size();
  for (const auto& f : fingerprints_) stats.stored_fingerprints += f ? 1 : 0;
  stats.candidate_index_bytes = index_ ? index_->bytes() : 0;
  return stats;
}

// ---- state (de)serialisation ---------------------------------------------------------------------

FrozenTopologyState TopologyParticleFilter::freeze() const {
  if (phase_ != Phase::Idle)
    throw std::logic_error("TopologyParticleFilter::saveState: a step is in progress");
  FrozenTopologyState frozen;
  frozen.config_ = config_;
  frozen.rng_ = rng_;
  frozen.observation_count_ = observation_count_;
  frozen.last_ess_ = last_ess_;
  frozen.degenerate_steps_ = degenerate_steps_;
  frozen.fingerprints_ = fingerprints_;
  frozen.particles_ = particles_;
  return frozen;
}

void TopologyParticleFilter::saveState(std::ostream& out) const { freeze().saveState(out); }

// Reads only immutable data (the scalars copied here, the fingerprints, and the history records'
// observation, node and parent), never the trie nodes' per-step memo fields, so the filter may step on
// another thread meanwhile. A history record's parent is only changed by its destructor, once nothing
// else (this state included) holds the record.
void FrozenTopologyState::saveState(std::ostream& out) const {
  std::string data;
  appendState(data);
  out.write(data.data(), static_cast<std::streamsize>(data.size()));
}

void FrozenTopologyState::appendState(std::string& out) const {
  BinaryWriter w(std::move(out));  // written in place at the end of `out`, given back below
  w.i32(config_.particles);
  w.f64(config_.alpha);
  w.f64(config_.new_node_probability);
  w.f64(config_.gamma_shape);
  w.f64(config_.gamma_scale);
  w.i32(config_.max_successors);
  w.i32(config_.max_representatives_per_node);
  w.u8(config_.forbid_return_to_previous ? 1 : 0);
  w.u64(config_.seed);
  std::ostringstream rng_text;
  rng_text << rng_;
  w.bytes(rng_text.str());
  w.i32(observation_count_);
  w.f64(last_ess_);
  w.i64(degenerate_steps_);

  std::uint32_t alive = 0;
  std::size_t descriptor_bytes = 0;
  for (const auto& f : fingerprints_)
    if (f) {
      ++alive;
      descriptor_bytes += f->descriptors.total() * f->descriptors.elemSize();
    }
  // A guess that avoids regrowing a buffer of hundreds of MB: descriptors plus ~3 KB per fingerprint
  // (keypoints, subregions) plus 12 bytes per history record.
  w.reserve(w.data().size() + descriptor_bytes + 3200u * alive + 24u * fingerprints_.size() + 4096u);
  w.u32(alive);
  for (std::size_t o = 0; o < fingerprints_.size(); ++o) {
    if (!fingerprints_[o]) continue;
    w.i32(static_cast<std::int32_t>(o));
    w.bytesFrom([&](std::string& bytes) { appendFingerprintBytes(bytes, *fingerprints_[o]); });
  }

  // History records reachable from the particles, parents before children (observation ascending).
  std::vector<const HistoryRecord*> records;
  std::unordered_map<const HistoryRecord*, std::int32_t> id;
  for (const auto& p : particles_) {
    for (const HistoryRecord* r = p->record.get(); r && id.emplace(r, 0).second; r = r->parent.get()) {
      records.push_back(r);
    }
  }
  std::stable_sort(records.begin(), records.end(), [](const HistoryRecord* a, const HistoryRecord* b) {
    return a->observation < b->observation;
  });
  for (std::size_t i = 0; i < records.size(); ++i) id[records[i]] = static_cast<std::int32_t>(i);
  w.u32(static_cast<std::uint32_t>(records.size()));
  for (const HistoryRecord* r : records) {
    w.i32(r->parent ? id.at(r->parent.get()) : -1);
    w.i32(r->observation);
    w.i32(r->node);
  }
  w.u32(static_cast<std::uint32_t>(particles_.size()));
  for (const auto& p : particles_) w.i32(p->record ? id.at(p->record.get()) : -1);
  // Extension block (absent in maps written before the likelihood model existed: those are absolute).
  w.u8(static_cast<std::uint8_t>(config_.likelihood));
  w.f64(config_.relative_slope);
  w.f64(config_.relative_offset);
  w.f64(config_.relative_sigma_floor);
  // Second extension block (absent in maps written before it: those used eq. 5.7's entropy).
  w.u8(config_.new_node_entropy ? 1 : 0);
  // Third extension block (absent in maps written before it: those had no floor).
  w.f64(config_.new_node_likelihood_floor);
  out = w.take();
}

std::unique_ptr<TopologyParticleFilter> TopologyParticleFilter::loadState(
    std::istream& in, const SimilarityMeasure& similarity) {
  std::string data;
  std::array<char, 65536> chunk{};
  while (in.read(chunk.data(), static_cast<std::streamsize>(chunk.size())) || in.gcount() > 0) {
    data.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
  }
  return loadState(std::string_view(data), similarity);
}

std::unique_ptr<TopologyParticleFilter> TopologyParticleFilter::loadState(
    std::string_view data, const SimilarityMeasure& similarity) {
  BinaryReader r(data);
  TopologyFilterConfig config;
  config.particles = r.i32("config");
  config.alpha = r.f64("config");
  config.new_node_probability = r.f64("config");
  config.gamma_shape = r.f64("config");
  config.gamma_scale = r.f64("config");
  config.max_successors = r.i32("config");
  config.max_representatives_per_node = r.i32("config");
  config.forbid_return_to_previous = r.flag("config");
  config.seed = r.u64("config");
  if (const std::string problem = config.validate(); !problem.empty()) {
    throw std::runtime_error("map data has an invalid filter config: " + problem);
  }
  auto filter = std::make_unique<TopologyParticleFilter>(config, similarity);
  {
    std::istringstream rng_text{std::string(r.bytes("random generator state"))};
    rng_text >> filter->rng_;
    if (rng_text.fail()) throw std::runtime_error("map data has a malformed random generator state");
  }
  const std::int32_t observations = r.i32("observation count");
  // Every observation has a history record (12 bytes) on each particle's lineage: bound the count by the
  // bytes left before allocating anything for it.
  if (observations < 0 || static_cast<std::uint64_t>(observations) > r.remaining() / 12) {
    throw std::runtime_error("map data has an impossible observation count " + std::to_string(observations));
  }
  filter->observation_count_ = observations;
  filter->stamp_ = static_cast<std::uint64_t>(observations);
  filter->last_ess_ = r.f64("effective sample size");
  filter->degenerate_steps_ = r.i64("degenerate steps");

  const std::uint32_t alive = r.u32("fingerprint count");
  if (alive > static_cast<std::uint32_t>(observations))
    throw std::runtime_error("map data has more fingerprints than observations");
  filter->fingerprints_.assign(idx(observations), nullptr);
  for (std::uint32_t k = 0; k < alive; ++k) {
    const std::int32_t o = r.i32("fingerprint index");
    if (o < 0 || o >= observations || filter->fingerprints_[idx(o)]) {
      throw std::runtime_error("map data has a bad fingerprint index " + std::to_string(o));
    }
    const std::string_view blob = r.bytes("fingerprint");
    std::shared_ptr<Fingerprint> fingerprint;
    try {
      fingerprint = std::make_shared<Fingerprint>(fingerprintFromBytes(blob));
    } catch (const std::exception& e) {
      throw std::runtime_error("map data has a malformed fingerprint of observation " + std::to_string(o) +
                               ": " + e.what());
    }
    if (const std::string problem = fingerprint->validate(); !problem.empty()) {
      throw std::runtime_error("map data has an invalid fingerprint of observation " + std::to_string(o) +
                               ": " + problem);
    }
    filter->fingerprints_[idx(o)] = std::move(fingerprint);
  }

  const std::uint32_t record_count = r.u32("history record count");
  if (record_count > r.remaining() / 12) throw std::runtime_error("map data truncated in history records");
  struct Rec {
    std::int32_t parent, observation, node;
  };
  std::vector<Rec> recs(record_count);
  std::vector<std::int32_t> remaining_children(record_count, 0);
  for (std::uint32_t i = 0; i < record_count; ++i) {
    Rec& rec = recs[i];
    rec.parent = r.i32("history record");
    rec.observation = r.i32("history record");
    rec.node = r.i32("history record");
    const bool root_ok = rec.parent == -1 && rec.observation == 0;
    const bool child_ok = rec.parent >= 0 && static_cast<std::uint32_t>(rec.parent) < i &&
                          rec.observation == recs[idx(rec.parent)].observation + 1;
    if (!(root_ok || child_ok) || rec.observation >= observations) {
      throw std::runtime_error("map data has an inconsistent history record " + std::to_string(i));
    }
    if (rec.parent >= 0) ++remaining_children[idx(rec.parent)];
  }
  const std::uint32_t particle_count = r.u32("particle count");
  if (particle_count != static_cast<std::uint32_t>(config.particles)) {
    throw std::runtime_error("map data has " + std::to_string(particle_count) + " particles, config says " +
                             std::to_string(config.particles));
  }
  std::vector<std::int32_t> tips(particle_count);
  std::vector<unsigned char> is_tip(record_count, 0);
  for (auto& t : tips) {
    t = r.i32("particles");
    const bool ok = observations == 0 ? t == -1
                                      : (t >= 0 && static_cast<std::uint32_t>(t) < record_count &&
                                         recs[idx(t)].observation == observations - 1);
    if (!ok) throw std::runtime_error("map data has a particle pointing at a bad history record");
    if (t >= 0) is_tip[idx(t)] = 1;
  }
  if (!r.atEnd()) {
    const std::uint8_t model = r.u8("likelihood model");
    if (model > static_cast<std::uint8_t>(LikelihoodModel::Relative))
      throw std::runtime_error("map data: unknown likelihood model " + std::to_string(model));
    config.likelihood = static_cast<LikelihoodModel>(model);
    config.relative_slope = r.f64("likelihood model");
    config.relative_offset = r.f64("likelihood model");
    config.relative_sigma_floor = r.f64("likelihood model");
    config.new_node_entropy = r.atEnd() ? true : r.flag("new node likelihood");
    config.new_node_likelihood_floor = r.atEnd() ? 0.0 : r.f64("new node likelihood floor");
    if (const std::string problem = config.validate(); !problem.empty())
      throw std::runtime_error("map data: bad filter config: " + problem);
  } else {
    config.likelihood = LikelihoodModel::Absolute;  // written before the likelihood model existed
  }
  if (!r.atEnd()) throw std::runtime_error("map data has trailing bytes after the particles");
  filter->config_ = config;  // the likelihood model came after the filter was made

  // Rebuild the shared states by replaying the record tree (extendState is what the filter ran).
  std::vector<std::shared_ptr<const TopologyState>> states(record_count);
  const auto empty = std::make_shared<const TopologyState>();
  for (std::uint32_t i = 0; i < record_count; ++i) {
    const Rec& rec = recs[i];
    const TopologyState& parent = rec.parent < 0 ? *empty : *states[idx(rec.parent)];
    if (rec.node < 0 || rec.node > parent.nodeCount()) {
      throw std::runtime_error("map data assigns observation " + std::to_string(rec.observation) +
                               " to a node that does not exist");
    }
    states[i] = topology_detail::extendState(parent, rec.observation, rec.node, config);
    if (rec.parent >= 0 && --remaining_children[idx(rec.parent)] == 0 && !is_tip[idx(rec.parent)]) {
      states[idx(rec.parent)].reset();
    }
  }
  for (std::uint32_t p = 0; p < particle_count; ++p) {
    filter->particles_[p] = tips[p] < 0 ? empty : states[idx(tips[p])];
  }
  // Every representative a particle refers to must have come with the file.
  std::vector<unsigned char> needed(idx(observations), 0);
  ++filter->stamp_;
  for (const auto& p : filter->particles_)
    markReferenced(p->nodes.root().get(), p->nodes.levels(), filter->stamp_, needed);
  for (std::size_t o = 0; o < needed.size(); ++o) {
    if (needed[o] && !filter->fingerprints_[o]) {
      throw std::runtime_error("map data lacks the fingerprint of observation " + std::to_string(o));
    }
  }
  return filter;
}

}  // namespace toposlam
