// n-gram matching of two VPACK fingerprints (thesis section 3.3.1, Figure 3.9): the one engine behind
// both the pairwise similarity (NgramSimilarity) and the localisation among places (PlaceLocalizer).
//
// Each subregion is a "letter". For a (reference, query) pair the engine
//   1. matches histograms: for every reference letter j, the query letter i with the smallest normalised
//      Hellinger distance d; kept if d <= max_hellinger_distance, letter score 1 - d (equal distances:
//      the letter after the previous reference letter's partner, else the same relative position);
//   2. matches keypoints: for every query keypoint, its best match among all the reference's keypoints
//      (Hamming distance for binary descriptors, L2 for float ones), kept if it passes the optional
//      distance and ratio tests (a best distance shared by several reference keypoints goes to the
//      order-consistent one, see docs/matching.md). Reference letter j and query letter i correspond when at least one
//      keypoint of i matched a keypoint of j; the pair's score is the number of distinct keypoints of j
//      matched from i over the number of keypoints in j;
//   3. counts n-grams (n = 1, 2, 3) separately for histograms and keypoints: an n-gram is n consecutive
//      reference letters j..j+n-1 corresponding to n consecutive query letters i..i+n-1 in the same
//      order; it counts the average of its n pair scores. A reference n-gram is counted at most once:
//      when several query positions i fit, the one with the largest average counts. So the count for n
//      is at most the number of n-grams the reference could have had (reported beside it).
// See docs/matching.md for the exact rules and measured numbers.
//
// Thread-safety: NgramMatcher is immutable after construction; all methods are const and may be called
// concurrently. The hot path (counts()) allocates nothing once a thread's scratch buffers have grown to
// the largest fingerprints seen (one thread_local MatchScratch per thread unless the caller passes one).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "toposlam/fingerprint/fingerprint.hpp"

namespace toposlam {

/// Unigrams, bigrams, trigrams (the thesis stops at 3, as usual in NLP).
inline constexpr int kMaxNgramOrder = 3;

struct NgramMatcherConfig {
  /// Histograms match when the normalised Hellinger distance (in [0, 1]) is at most this (thesis: 0.3).
  double max_hellinger_distance = 0.3;
  /// Binary descriptors: a keypoint match is kept when its Hamming distance is at most this fraction of
  /// the descriptor's bits (ORB: 256 bits, so 0.25 = 64 bits). 1 disables the test (thesis: optional).
  double max_binary_distance_fraction = 0.25;
  /// Float descriptors (SIFT, unnormalised, norms around 512): maximum L2 distance; 0 disables the test.
  double max_float_distance = 0.0;
  /// Lowe's ratio test: kept when best <= ratio * second best among the reference's keypoints.
  /// 1 disables it. Default 0.9 (measured on the samples, docs/matching.md).
  double ratio_test = 0.9;
  /// Mutual check: a match is kept only when the query keypoint is also the reference keypoint's best
  /// match among the query's keypoints (thesis: no; measured on real frames, docs/matching.md).
  bool mutual_check = false;
  /// Orientation check: a match is kept only when the two keypoints' orientations differ by at most
  /// this many degrees (an upright camera sees a revisited point at nearly its old orientation; random
  /// matches are spread over all 360). 0 disables it (thesis: no).
  double max_angle_difference_deg = 0.0;
  /// Returns "" when valid, else "<key>: <problem, allowed range>".
  std::string validate() const;
};

/// n-gram counts of one (reference, query) pair, index [n - 1] for n = 1, 2, 3.
struct NgramCounts {
  /// Sum over matched n-grams of the average of their letters' scores ("effective" n-grams).
  std::array<double, kMaxNgramOrder> histogram{};
  std::array<double, kMaxNgramOrder> keypoint{};
  /// Number of matched n-grams (each counts 1 regardless of its score).
  std::array<int, kMaxNgramOrder> histogram_matched{};
  std::array<int, kMaxNgramOrder> keypoint_matched{};
  /// n-grams the reference could have had: histograms, max(0, letters - n + 1); keypoints, windows of n
  /// consecutive reference letters that all own at least one keypoint.
  std::array<int, kMaxNgramOrder> histogram_possible{};
  std::array<int, kMaxNgramOrder> keypoint_possible{};
  int query_keypoints = 0;
  int reference_keypoints = 0;
  int query_letters = 0;  ///< subregions of the query
  int matched_keypoints = 0;  ///< query keypoints whose best match passed the tests
  /// Verified matches (distinct reference keypoints per letter pair) that lie in a letter pair belonging
  /// to at least one complete keypoint n-gram of order n: [0] all of them, [1] those on a bigram, ...
  std::array<int, kMaxNgramOrder> keypoint_ngram_matches{};
  /// The most verified matches on one order-preserving alignment of letters (reference letters and
  /// query letters both increasing): the n-gram order check without requiring consecutive letters.
  int aligned_matches = 0;
};

/// One corresponding letter pair with its score (for explanations, drawings and tests; not hot).
struct LetterCorrespondence {
  int reference_letter = 0;
  int query_letter = 0;
  double score = 0.0;  ///< histograms: 1 - d; keypoints: matched keypoints of the reference letter / its keypoints
  int matched_keypoints = 0;  ///< keypoints only: distinct reference keypoints of the letter matched from the query letter
};

struct LetterCorrespondences {
  std::vector<LetterCorrespondence> histogram;  ///< at most one per reference letter
  std::vector<LetterCorrespondence> keypoint;   ///< any number per reference letter
};

/// Best match of one query keypoint among a reference's keypoints.
struct DescriptorMatch {
  int reference_keypoint = -1;  ///< row in the reference's descriptor matrix, -1 if it has none
  float distance = 0.f;         ///< Hamming bits (binary) or L2 (float)
  float second_distance = 0.f;  ///< second best distance, +infinity when there is none
};

/// Reusable buffers of the matcher. One per thread; never shared between threads at the same time.
struct MatchScratch {
  std::vector<double> reference_sqrt_histograms;  ///< letters x 13: sqrt(bin / sum of bins)
  std::vector<double> query_sqrt_histograms;
  std::vector<std::uint8_t> reference_histogram_empty;
  std::vector<std::uint8_t> query_histogram_empty;
  std::vector<float> histogram_scores;  ///< reference letters x query letters, 0 = no correspondence
  std::vector<float> keypoint_scores;   ///< same layout
  std::vector<std::uint64_t> reference_words;  ///< binary descriptors padded to whole 64-bit words
  std::vector<std::uint64_t> query_words;
  std::vector<int> reference_letter_of_keypoint;
  std::vector<int> last_query_letter;  ///< per reference keypoint: last query letter that matched it
  std::vector<int> pair_matches;       ///< reference letters x query letters, distinct matched keypoints
  std::vector<DescriptorMatch> matches;  ///< per query keypoint
  std::vector<int> reference_best;       ///< per reference keypoint: its best query keypoint (mutual check)
  std::vector<int> reference_best_bits;  ///< scratch of the binary kernel
  std::vector<float> reference_best_l2;  ///< scratch of the float kernel
  std::vector<int> alignment;            ///< reference letters x query letters, alignment DP
  // The reverse direction of the last binary pass, kept by countsBothWays() for its second half.
  std::vector<DescriptorMatch> reverse_matches;  ///< per reference keypoint: its best query keypoint
  std::vector<int> reverse_reference_best;       ///< per query keypoint: its best reference keypoint
  std::vector<int> reference_second_bits;        ///< scratch of the both-ways binary kernel
  bool reverse_ready = false;
};

class NgramMatcher {
 public:
  /// Throws std::invalid_argument naming the bad key when the config is invalid.
  explicit NgramMatcher(const NgramMatcherConfig& config = {});
  const NgramMatcherConfig& config() const { return config_; }

  /// n-gram counts of `query` against `reference`. scratch = nullptr uses this thread's own buffers.
  /// Fingerprints with different descriptor types or lengths get no keypoint matches (histograms still
  /// count). Never throws on well-formed fingerprints (Fingerprint::validate() == "").
  NgramCounts counts(const Fingerprint& reference, const Fingerprint& query,
                     MatchScratch* scratch = nullptr) const;

  /// counts(a, b) and counts(b, a), equal to the two calls to the last bit, with one descriptor pass for
  /// both directions when the descriptors are binary (a symmetric similarity's cost nearly halved).
  std::pair<NgramCounts, NgramCounts> countsBothWays(const Fingerprint& a, const Fingerprint& b,
                                                     MatchScratch* scratch = nullptr) const;

  /// The letter correspondences behind counts() (allocates; for the CLI, drawings and tests).
  LetterCorrespondences correspondences(const Fingerprint& reference, const Fingerprint& query) const;

  /// Normalised Hellinger distance of two 13-bin histograms, in [0, 1] (eq. 3.3/3.4). Histograms are
  /// divided by their sums first; two empty (all-zero) histograms are at distance 0, one empty at 1.
  static double hellingerDistance(const HclHistogramBins& a, const HclHistogramBins& b);

  /// Hamming distance of two binary descriptor rows of `bytes` bytes (any length).
  static int hammingDistance(const std::uint8_t* a, const std::uint8_t* b, int bytes);

  /// Sum of the average pair scores of n-grams along diagonals of a (reference x query) score matrix
  /// (row-major, 0 = no correspondence): the counting rule of step 3, exposed for tests.
  /// matched receives the number of counted n-grams.
  static double countNgrams(const float* scores, int reference_letters, int query_letters, int n,
                            int* matched);

 private:
  /// What a binary descriptor pass does with the reverse direction: nothing, keep it in the scratch (the
  /// first half of countsBothWays), or take the kept one instead of a pass (the second half).
  enum class ReversePass { None, Keep, Take };
  NgramCounts countsWith(const Fingerprint& reference, const Fingerprint& query, MatchScratch& s,
                         ReversePass reverse) const;
  void matchHistograms(const Fingerprint& reference, const Fingerprint& query, MatchScratch& s) const;
  /// Returns the number of query keypoints whose match was kept.
  int matchKeypoints(const Fingerprint& reference, const Fingerprint& query, MatchScratch& s,
                     ReversePass reverse = ReversePass::None) const;
  /// Fills keypoint_ngram_matches and aligned_matches from s.pair_matches (m x q).
  static void verifiedMatchCounts(int m, int q, MatchScratch& s, NgramCounts& result);

  NgramMatcherConfig config_;
};

}  // namespace toposlam
