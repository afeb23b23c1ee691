// TopologyParticleFilter's state as bytes: freeze() and saveState() write the config, the random
// generator, the stored representatives, the shared history records and the particles; loadState() reads
// them back, checks them and rebuilds the shared states by replaying the history. Little-endian; MapStore
// frames, versions and checksums it. See the header.
#include <algorithm>
#include <array>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "binary_io.hpp"
#include "node_likelihoods.hpp"
#include "topology_state.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam {

using topology_detail::BinaryReader;
using topology_detail::BinaryWriter;
using topology_detail::HistoryRecord;
using topology_detail::idx;
using topology_detail::markReferenced;
using topology_detail::TopologyState;

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

namespace {

// loadState's steps, in the order of the bytes. Each throws std::runtime_error naming what is malformed.

/// The config fields written first (the likelihood model's come in the extension blocks).
TopologyFilterConfig readConfig(BinaryReader& r) {
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
  return config;
}

/// The stored representatives, by observation (null: dropped).
std::vector<std::shared_ptr<const Fingerprint>> readFingerprints(BinaryReader& r, std::int32_t observations) {
  const std::uint32_t alive = r.u32("fingerprint count");
  if (alive > static_cast<std::uint32_t>(observations))
    throw std::runtime_error("map data has more fingerprints than observations");
  std::vector<std::shared_ptr<const Fingerprint>> fingerprints(idx(observations), nullptr);
  for (std::uint32_t k = 0; k < alive; ++k) {
    const std::int32_t o = r.i32("fingerprint index");
    if (o < 0 || o >= observations || fingerprints[idx(o)]) {
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
    fingerprints[idx(o)] = std::move(fingerprint);
  }
  return fingerprints;
}

/// One history record as written: parent record index (-1 for the first observation), observation, node.
struct SavedRecord {
  std::int32_t parent, observation, node;
};

/// The history records, parents before children; `children` counts each record's children.
std::vector<SavedRecord> readHistory(BinaryReader& r, std::int32_t observations, std::vector<std::int32_t>& children) {
  const std::uint32_t record_count = r.u32("history record count");
  if (record_count > r.remaining() / 12) throw std::runtime_error("map data truncated in history records");
  std::vector<SavedRecord> recs(record_count);
  children.assign(record_count, 0);
  for (std::uint32_t i = 0; i < record_count; ++i) {
    SavedRecord& rec = recs[i];
    rec.parent = r.i32("history record");
    rec.observation = r.i32("history record");
    rec.node = r.i32("history record");
    const bool root_ok = rec.parent == -1 && rec.observation == 0;
    const bool child_ok = rec.parent >= 0 && static_cast<std::uint32_t>(rec.parent) < i &&
                          rec.observation == recs[idx(rec.parent)].observation + 1;
    if (!(root_ok || child_ok) || rec.observation >= observations) {
      throw std::runtime_error("map data has an inconsistent history record " + std::to_string(i));
    }
    if (rec.parent >= 0) ++children[idx(rec.parent)];
  }
  return recs;
}

/// Each particle's last history record (-1 before the first observation); `is_tip` marks those records.
std::vector<std::int32_t> readParticleTips(BinaryReader& r, const TopologyFilterConfig& config,
                                           std::int32_t observations, const std::vector<SavedRecord>& recs,
                                           std::vector<unsigned char>& is_tip) {
  const std::uint32_t particle_count = r.u32("particle count");
  if (particle_count != static_cast<std::uint32_t>(config.particles)) {
    throw std::runtime_error("map data has " + std::to_string(particle_count) + " particles, config says " +
                             std::to_string(config.particles));
  }
  const auto record_count = static_cast<std::uint32_t>(recs.size());
  std::vector<std::int32_t> tips(particle_count);
  is_tip.assign(record_count, 0);
  for (auto& t : tips) {
    t = r.i32("particles");
    const bool ok = observations == 0 ? t == -1
                                      : (t >= 0 && static_cast<std::uint32_t>(t) < record_count &&
                                         recs[idx(t)].observation == observations - 1);
    if (!ok) throw std::runtime_error("map data has a particle pointing at a bad history record");
    if (t >= 0) is_tip[idx(t)] = 1;
  }
  return tips;
}

/// The extension blocks after the particles (each absent in maps written before it) into `config`.
void readConfigExtensions(BinaryReader& r, TopologyFilterConfig& config) {
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
}

/// The shared states at the particles' tips, rebuilt by replaying the record tree (extendState is what the
/// filter ran). A state is let go as soon as its last child is made, unless a particle holds it.
std::vector<std::shared_ptr<const TopologyState>> replayHistory(const std::vector<SavedRecord>& recs,
                                                                std::vector<std::int32_t>& remaining_children,
                                                                const std::vector<unsigned char>& is_tip,
                                                                const TopologyFilterConfig& config) {
  std::vector<std::shared_ptr<const TopologyState>> states(recs.size());
  const auto empty = std::make_shared<const TopologyState>();
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const SavedRecord& rec = recs[i];
    const TopologyState& parent = rec.parent < 0 ? *empty : *states[idx(rec.parent)];
    if (rec.node < 0 || rec.node > parent.nodeCount()) {
      throw std::runtime_error("map data assigns observation " + std::to_string(rec.observation) +
                               " to a node that does not exist");
    }
    states[i] = topology_detail::extendState(parent, rec.observation, rec.node, config.max_successors,
                                              config.max_representatives_per_node);
    if (rec.parent >= 0 && --remaining_children[idx(rec.parent)] == 0 && !is_tip[idx(rec.parent)]) {
      states[idx(rec.parent)].reset();
    }
  }
  return states;
}

}  // namespace

std::unique_ptr<TopologyParticleFilter> TopologyParticleFilter::loadState(
    std::string_view data, const SimilarityMeasure& similarity) {
  BinaryReader r(data);
  TopologyFilterConfig config = readConfig(r);
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
  filter->fingerprints_ = readFingerprints(r, observations);

  std::vector<std::int32_t> remaining_children;
  const std::vector<SavedRecord> recs = readHistory(r, observations, remaining_children);
  std::vector<unsigned char> is_tip;
  const std::vector<std::int32_t> tips = readParticleTips(r, config, observations, recs, is_tip);
  readConfigExtensions(r, config);
  filter->config_ = config;  // the likelihood model came after the filter was made

  const std::vector<std::shared_ptr<const TopologyState>> states =
      replayHistory(recs, remaining_children, is_tip, config);
  const auto empty = std::make_shared<const TopologyState>();
  for (std::size_t p = 0; p < tips.size(); ++p) {
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
