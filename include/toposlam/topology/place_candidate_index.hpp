// PlaceCandidateIndex: which stored places a new place's representative most likely matches, found
// without comparing it with every one of them (issue 18: the cost of a new place must not grow with the
// map). Built online from the stored places' own binary descriptors (ORB, BRISK, AKAZE-MLDB): no
// training, no vocabulary file.
//
// Locality-sensitive hashing by bit sampling: each of `tables` hash tables reads `bits_per_key` fixed bit
// positions of a descriptor (chosen once from `seed`) and files the place under that key. Two descriptors
// d bits apart share a table's key with probability (1 - d/D)^bits (D = descriptor bits), so a keypoint
// seen again (a few tens of bits apart) shares some key in most tables, while unrelated descriptors (about
// D/2 apart) almost never do. A query votes, per descriptor and table, for every place filed under its
// key; the places with the most votes are the candidates. Keys that are crowded (more entries than
// `crowded_share` of the stored places, the index's stop words) are skipped at query time: they say
// nothing about which place it is.
//
// Fingerprints with float descriptors (SIFT) or none are not indexed (supports() is false for them); the
// caller then compares exhaustively. Memory: tables x 2^bits bucket headers once the first place is added,
// plus 4 bytes per stored descriptor and table.
//
// Thread-safety: none (candidates() uses member scratch); one instance per filter, used from one thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "toposlam/fingerprint/fingerprint.hpp"

namespace toposlam {

struct PlaceCandidateIndexConfig {
  int tables = 8;               ///< hash tables; allowed [1, 32]
  int bits_per_key = 14;        ///< sampled descriptor bits per key; allowed [4, 20], tables x 2^bits <= 2^21
  double crowded_share = 0.05;  ///< a key holding more entries than this share of places is skipped; (0, 1]
  std::uint64_t seed = 1;       ///< of the bit positions
  /// "" when valid, else "<key>: <problem, allowed range>".
  std::string validate() const;
};

class PlaceCandidateIndex {
 public:
  /// Throws std::invalid_argument with validate()'s message.
  explicit PlaceCandidateIndex(const PlaceCandidateIndexConfig& config = {});

  /// True when `fingerprint` has binary descriptors (the only kind indexed).
  static bool supports(const Fingerprint& fingerprint);
  /// Files place `place` (>= 0, each id at most once while stored) under its descriptors' keys. A
  /// fingerprint supports() refuses is ignored. Descriptors shorter than the sampled bit positions need
  /// are ignored too (all ORB/BRISK/AKAZE descriptors are 32 bytes or more).
  void add(int place, const Fingerprint& fingerprint);
  /// Removes place `place`, added with the same `fingerprint`. Unknown places are ignored.
  void remove(int place, const Fingerprint& fingerprint);
  /// Up to `count` stored places, most votes first (ties: lower id first); only places with at least one
  /// vote. Deterministic.
  std::vector<int> candidates(const Fingerprint& query, int count);

  std::size_t places() const { return places_; }
  /// Heap bytes held (bucket headers and entries), for benchmarks.
  std::size_t bytes() const;
  const PlaceCandidateIndexConfig& config() const { return config_; }

 private:
  /// The key of descriptor row `row` in table `table`, or false when the row is too short.
  bool keyOf(const std::uint8_t* row, int row_bytes, int table, std::uint32_t& key) const;
  /// keys_ := the bucket (table << bits | key) of every descriptor row and table, rows first.
  void bucketsOf(const Fingerprint& fingerprint);

  PlaceCandidateIndexConfig config_;
  std::vector<std::uint16_t> bit_positions_;           ///< tables x bits_per_key
  std::vector<std::vector<std::uint32_t>> buckets_;    ///< tables x 2^bits, place ids (repeats allowed)
  std::size_t places_ = 0;
  std::size_t entries_ = 0;
  int max_bit_ = 0;  ///< largest sampled bit position + 1
  // Query scratch.
  std::vector<std::uint32_t> votes_;
  std::vector<std::uint32_t> touched_;
  std::vector<std::uint32_t> keys_;  ///< bucketsOf()'s result (add() and candidates())
};

}  // namespace toposlam
