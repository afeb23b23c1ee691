// Test helpers for the topology filter: fingerprints that carry only a tag (their image width - 1), and
// a SimilarityMeasure that looks the similarity of two tags up in a hand-made function, a small filter.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <vector>

#include "toposlam/fingerprint/fingerprint.hpp"
#include "toposlam/matching/similarity_measure.hpp"
#include "toposlam/topology/topology_particle_filter.hpp"

namespace toposlam::test {

/// A valid, keypoint-free fingerprint whose tag is image_width - 1.
inline std::shared_ptr<const Fingerprint> taggedFingerprint(int tag) {
  auto f = std::make_shared<Fingerprint>();
  f->image_width = tag + 1;
  f->image_height = 1;
  Subregion whole;
  whole.column_begin = 0;
  whole.column_end = tag + 1;
  f->subregions.push_back(whole);
  return f;
}

inline int tagOf(const Fingerprint& f) { return f.image_width - 1; }

class TagSimilarity : public SimilarityMeasure {
 public:
  explicit TagSimilarity(std::function<double(int reference_tag, int query_tag)> table)
      : table_(std::move(table)) {}
  double similarity(const Fingerprint& reference, const Fingerprint& query) const override {
    calls_.fetch_add(1);
    return table_(tagOf(reference), tagOf(query));
  }
  long calls() const { return calls_.load(); }

 private:
  std::function<double(int, int)> table_;
  mutable std::atomic<long> calls_{0};
};

/// Same place (tag) -> `same`, else `different`.
inline TagSimilarity placeSimilarity(double same = 0.9, double different = 0.1) {
  return TagSimilarity([=](int a, int b) { return a == b ? same : different; });
}

/// A 50-particle filter (seed 3) stepped `steps` times over the tags 0, 1, 2, 3, 0, ...: a small map.
inline std::unique_ptr<TopologyParticleFilter> smallFilter(const SimilarityMeasure& similarity, int steps) {
  TopologyFilterConfig config;
  config.particles = 50;
  config.seed = 3;
  auto filter = std::make_unique<TopologyParticleFilter>(config, similarity);
  for (int k = 0; k < steps; ++k) filter->step(taggedFingerprint(k % 4));
  return filter;
}

}  // namespace toposlam::test
