// PlaceCandidateIndex: bit-sampling LSH tables over binary descriptors, votes per place. See the header.
#include "toposlam/topology/place_candidate_index.hpp"

#include <algorithm>
#include <numeric>
#include <random>
#include <stdexcept>

namespace toposlam {

namespace {

/// Bit positions are drawn from the first 256 bits, the length of the shortest binary descriptor we make
/// (ORB, 32 bytes), so one index serves ORB, BRISK and AKAZE alike.
constexpr int kSampledBits = 256;

/// A hint to the CPU to fetch `address` into the cache (no effect on results).
inline void prefetch(const void* address) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(address);
#else
  (void)address;
#endif
}

}  // namespace

std::string PlaceCandidateIndexConfig::validate() const {
  if (tables < 1 || tables > 32) return "tables: must be in [1, 32]";
  if (bits_per_key < 4 || bits_per_key > 20) return "bits_per_key: must be in [4, 20]";
  if (!(crowded_share > 0.0 && crowded_share <= 1.0)) return "crowded_share: must be in (0, 1]";
  if ((static_cast<long long>(tables) << bits_per_key) > (1LL << 21))
    return "bits_per_key: tables x 2^bits_per_key must be at most 2^21 buckets";
  return "";
}

PlaceCandidateIndex::PlaceCandidateIndex(const PlaceCandidateIndexConfig& config) : config_(config) {
  if (const std::string problem = config_.validate(); !problem.empty()) throw std::invalid_argument(problem);
  std::mt19937_64 rng(config_.seed);
  std::vector<std::uint16_t> all(kSampledBits);
  std::iota(all.begin(), all.end(), std::uint16_t{0});
  for (int t = 0; t < config_.tables; ++t) {
    // Partial Fisher-Yates with our own draws (std::shuffle's are not specified across libraries).
    for (int b = 0; b < config_.bits_per_key; ++b) {
      const auto left = static_cast<std::uint64_t>(kSampledBits - b);
      const auto pick = static_cast<std::size_t>(b) + static_cast<std::size_t>(rng() % left);
      std::swap(all[static_cast<std::size_t>(b)], all[pick]);
      bit_positions_.push_back(all[static_cast<std::size_t>(b)]);
      max_bit_ = std::max(max_bit_, all[static_cast<std::size_t>(b)] + 1);
    }
  }
}

bool PlaceCandidateIndex::supports(const Fingerprint& fingerprint) {
  return fingerprint.descriptorKind() == DescriptorKind::Binary && !fingerprint.descriptors.empty() &&
         fingerprint.descriptors.type() == CV_8U;
}

bool PlaceCandidateIndex::keyOf(const std::uint8_t* row, int row_bytes, int table, std::uint32_t& key) const {
  if (row_bytes * 8 < max_bit_) return false;
  const std::uint16_t* bits = bit_positions_.data() + static_cast<std::size_t>(table) * config_.bits_per_key;
  std::uint32_t k = 0;
  for (int b = 0; b < config_.bits_per_key; ++b) {
    const int bit = bits[b];
    k = (k << 1) | ((row[bit >> 3] >> (bit & 7)) & 1u);
  }
  key = k;
  return true;
}

void PlaceCandidateIndex::bucketsOf(const Fingerprint& fingerprint) {
  keys_.clear();
  const cv::Mat& d = fingerprint.descriptors;
  for (int r = 0; r < d.rows; ++r) {
    for (int t = 0; t < config_.tables; ++t) {
      std::uint32_t key = 0;
      if (!keyOf(d.ptr<std::uint8_t>(r), d.cols, t, key)) continue;
      keys_.push_back(static_cast<std::uint32_t>((static_cast<std::size_t>(t) << config_.bits_per_key) | key));
    }
  }
}

void PlaceCandidateIndex::add(int place, const Fingerprint& fingerprint) {
  if (place < 0 || !supports(fingerprint)) return;
  if (buckets_.empty()) buckets_.resize(static_cast<std::size_t>(config_.tables) << config_.bits_per_key);
  bucketsOf(fingerprint);
  for (const std::uint32_t b : keys_) prefetch(&buckets_[b]);
  for (const std::uint32_t b : keys_) {
    const auto& bucket = buckets_[b];
    if (bucket.size() < bucket.capacity()) prefetch(bucket.data() + bucket.size());
  }
  for (const std::uint32_t b : keys_) buckets_[b].push_back(static_cast<std::uint32_t>(place));
  entries_ += keys_.size();
  ++places_;
}

void PlaceCandidateIndex::remove(int place, const Fingerprint& fingerprint) {
  if (place < 0 || !supports(fingerprint) || buckets_.empty()) return;
  const cv::Mat& d = fingerprint.descriptors;
  bool found = false;
  for (int r = 0; r < d.rows; ++r) {
    for (int t = 0; t < config_.tables; ++t) {
      std::uint32_t key = 0;
      if (!keyOf(d.ptr<std::uint8_t>(r), d.cols, t, key)) continue;
      auto& bucket = buckets_[(static_cast<std::size_t>(t) << config_.bits_per_key) | key];
      const auto it = std::find(bucket.begin(), bucket.end(), static_cast<std::uint32_t>(place));
      if (it == bucket.end()) continue;
      *it = bucket.back();  // order inside a bucket does not matter: votes are counted
      bucket.pop_back();
      --entries_;
      found = true;
    }
  }
  if (found) --places_;
}

std::vector<int> PlaceCandidateIndex::candidates(const Fingerprint& query, int count) {
  std::vector<int> out;
  if (count <= 0 || !supports(query) || buckets_.empty()) return out;
  const auto crowded = static_cast<std::size_t>(std::max(8.0, config_.crowded_share * static_cast<double>(places_)));
  touched_.clear();
  // The buckets lie anywhere in a few MB: ask for all their headers, then all their first entries, before
  // reading any, so the cache misses overlap instead of coming one after another (same votes, same order).
  bucketsOf(query);
  for (const std::uint32_t b : keys_) prefetch(&buckets_[b]);
  for (const std::uint32_t b : keys_) {
    const auto& bucket = buckets_[b];
    if (!bucket.empty() && bucket.size() <= crowded) prefetch(bucket.data());
  }
  for (const std::uint32_t b : keys_) {
    const auto& bucket = buckets_[b];
    if (bucket.size() > crowded) continue;
    for (const std::uint32_t place : bucket) {
      if (place >= votes_.size()) votes_.resize(static_cast<std::size_t>(place) + 1, 0);
      if (votes_[place]++ == 0) touched_.push_back(place);
    }
  }
  const auto better = [&](std::uint32_t a, std::uint32_t b) {
    return votes_[a] != votes_[b] ? votes_[a] > votes_[b] : a < b;
  };
  const std::size_t keep = std::min(touched_.size(), static_cast<std::size_t>(count));
  std::partial_sort(touched_.begin(), touched_.begin() + static_cast<std::ptrdiff_t>(keep), touched_.end(), better);
  out.reserve(keep);
  for (std::size_t i = 0; i < keep; ++i) out.push_back(static_cast<int>(touched_[i]));
  for (const std::uint32_t place : touched_) votes_[place] = 0;
  return out;
}

std::size_t PlaceCandidateIndex::bytes() const {
  std::size_t total = buckets_.capacity() * sizeof(std::vector<std::uint32_t>);
  for (const auto& bucket : buckets_) total += bucket.capacity() * sizeof(std::uint32_t);
  return total + (votes_.capacity() + touched_.capacity() + keys_.capacity()) * sizeof(std::uint32_t);
}

}  // namespace toposlam
