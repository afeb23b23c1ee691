// n-gram matching of two VPACK fingerprints (thesis section 3.3.1): see ngram_matcher.hpp.
#include "toposlam/matching/ngram_matcher.hpp"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>

#include "descriptor_kernels.hpp"

namespace toposlam {
namespace {

MatchScratch& threadScratch() {
  thread_local MatchScratch scratch;
  return scratch;
}

// Grows a buffer without shrinking it, so a warm scratch never allocates again.
template <typename T>
void resizeFor(std::vector<T>& buffer, std::size_t size, const T& value) {
  if (buffer.capacity() < size) buffer.reserve(std::max(size, 2 * buffer.capacity()));
  buffer.assign(size, value);
}

// sqrt(bin / sum) per bin, so rho(Q, R) is a plain dot product. Returns false for an empty histogram.
bool sqrtHistogram(const HclHistogramBins& bins, double* out) {
  double sum = 0.0;
  for (float value : bins) sum += std::max(0.f, value);
  if (!(sum > 0.0)) {
    std::fill(out, out + kHistogramBins, 0.0);
    return false;
  }
  for (int b = 0; b < kHistogramBins; ++b) out[b] = std::sqrt(std::max(0.f, bins[b]) / sum);
  return true;
}

double hellingerFromSqrt(const double* a, bool a_empty, const double* b, bool b_empty) {
  if (a_empty || b_empty) return a_empty && b_empty ? 0.0 : 1.0;
  double rho = 0.0;
  for (int k = 0; k < kHistogramBins; ++k) rho += a[k] * b[k];
  return std::sqrt(std::clamp(1.0 - rho, 0.0, 1.0));
}

// Descriptor rows usable for matching: one channel, CV_8U or CV_32F, at least one row and column.
bool hasDescriptors(const Fingerprint& f) {
  return !f.descriptors.empty() && f.descriptors.channels() == 1 &&
         (f.descriptors.depth() == CV_8U || f.descriptors.depth() == CV_32F);
}

// Copies binary rows into zero-padded 64-bit words (words per row = ceil(bytes / 8)).
void packBinaryRows(const cv::Mat& rows, int words, std::vector<std::uint64_t>& out) {
  resizeFor(out, static_cast<std::size_t>(rows.rows) * static_cast<std::size_t>(words), std::uint64_t{0});
  const std::size_t bytes = static_cast<std::size_t>(rows.cols);
  for (int r = 0; r < rows.rows; ++r) {
    std::memcpy(out.data() + static_cast<std::size_t>(r) * static_cast<std::size_t>(words), rows.ptr<std::uint8_t>(r),
                bytes);
  }
}

// Clamped keypoint range of a subregion against the descriptor matrix (defensive: validate() should
// already guarantee it).
void keypointRange(const Subregion& s, int rows, int& begin, int& end) {
  begin = std::clamp(s.keypoint_begin, 0, rows);
  end = std::clamp(s.keypoint_end, begin, rows);
}

// Histogram distances closer than this are equally good (rounding of identical histograms).
constexpr double kHistogramTie = 1e-6;

// Tie-break cost of pairing letter `own` (of `own_letters`) with candidate letter `other` (of
// `other_letters`); lower wins. With a preferred candidate (the one that continues the previous letter's
// correspondence, -1 if none) the distance to it, else the distance to the same relative position,
// |own / own_letters - other / other_letters| scaled to integers. Equal costs keep the earlier candidate.
long orderCost(int own, int other, int own_letters, int other_letters, int preferred) {
  if (preferred >= 0) return std::labs(static_cast<long>(other) - preferred);
  return std::labs(static_cast<long>(other) * own_letters - static_cast<long>(own) * other_letters);
}

}  // namespace

std::string NgramMatcherConfig::validate() const {
  if (!(max_hellinger_distance > 0.0 && max_hellinger_distance <= 1.0))
    return "max_hellinger_distance: must be in (0, 1] (thesis: 0.3)";
  if (!(max_binary_distance_fraction > 0.0 && max_binary_distance_fraction <= 1.0))
    return "max_binary_distance_fraction: must be in (0, 1] (1 disables the test)";
  if (!(max_float_distance >= 0.0) || !std::isfinite(max_float_distance))
    return "max_float_distance: must be >= 0 (0 disables the test)";
  if (!(ratio_test > 0.0 && ratio_test <= 1.0)) return "ratio_test: must be in (0, 1] (1 disables the test)";
  if (!(max_angle_difference_deg >= 0.0 && max_angle_difference_deg <= 180.0))
    return "max_angle_difference_deg: must be in [0, 180] (0 disables the test)";
  return "";
}

NgramMatcher::NgramMatcher(const NgramMatcherConfig& config) : config_(config) {
  const std::string problem = config_.validate();
  if (!problem.empty()) throw std::invalid_argument("matching config: " + problem);
}

double NgramMatcher::hellingerDistance(const HclHistogramBins& a, const HclHistogramBins& b) {
  double sa[kHistogramBins];
  double sb[kHistogramBins];
  const bool a_full = sqrtHistogram(a, sa);
  const bool b_full = sqrtHistogram(b, sb);
  return hellingerFromSqrt(sa, !a_full, sb, !b_full);
}

int NgramMatcher::hammingDistance(const std::uint8_t* a, const std::uint8_t* b, int bytes) {
  int distance = 0;
  int i = 0;
  for (; i + 8 <= bytes; i += 8) {
    std::uint64_t wa = 0;
    std::uint64_t wb = 0;
    std::memcpy(&wa, a + i, 8);
    std::memcpy(&wb, b + i, 8);
    distance += std::popcount(wa ^ wb);
  }
  for (; i < bytes; ++i) distance += std::popcount(static_cast<unsigned>(a[i] ^ b[i]));
  return distance;
}

double NgramMatcher::countNgrams(const float* scores, int reference_letters, int query_letters, int n,
                                 int* matched) {
  double total = 0.0;
  int found = 0;
  for (int j = 0; j + n <= reference_letters; ++j) {
    double best = -1.0;
    for (int i = 0; i + n <= query_letters; ++i) {
      double sum = 0.0;
      bool complete = true;
      for (int t = 0; t < n; ++t) {
        const float score = scores[static_cast<std::ptrdiff_t>(j + t) * query_letters + (i + t)];
        if (!(score > 0.f)) {
          complete = false;
          break;
        }
        sum += score;
      }
      if (complete) best = std::max(best, sum / n);
    }
    if (best >= 0.0) {
      total += best;
      ++found;
    }
  }
  if (matched != nullptr) *matched = found;
  return total;
}

void NgramMatcher::matchHistograms(const Fingerprint& reference, const Fingerprint& query,
                                   MatchScratch& s) const {
  const int m = static_cast<int>(reference.subregions.size());
  const int q = static_cast<int>(query.subregions.size());
  resizeFor(s.histogram_scores, static_cast<std::size_t>(m) * static_cast<std::size_t>(q), 0.f);
  if (m == 0 || q == 0) return;
  resizeFor(s.reference_sqrt_histograms, static_cast<std::size_t>(m) * kHistogramBins, 0.0);
  resizeFor(s.query_sqrt_histograms, static_cast<std::size_t>(q) * kHistogramBins, 0.0);
  resizeFor(s.reference_histogram_empty, static_cast<std::size_t>(m), std::uint8_t{0});
  resizeFor(s.query_histogram_empty, static_cast<std::size_t>(q), std::uint8_t{0});
  for (int j = 0; j < m; ++j) {
    s.reference_histogram_empty[j] =
        sqrtHistogram(reference.subregions[j].histogram, &s.reference_sqrt_histograms[j * kHistogramBins]) ? 0 : 1;
  }
  for (int i = 0; i < q; ++i) {
    s.query_histogram_empty[i] =
        sqrtHistogram(query.subregions[i].histogram, &s.query_sqrt_histograms[i * kHistogramBins]) ? 0 : 1;
  }
  // For every reference histogram, its best query histogram, if close enough. Equally good candidates
  // (within kHistogramTie) resolve to the order-consistent one: the letter after the previous reference
  // letter's partner, else the one at the same relative position (see orderCost).
  int previous_partner = -1;
  for (int j = 0; j < m; ++j) {
    double best = std::numeric_limits<double>::infinity();
    int best_letter = -1;
    long best_cost = 0;
    for (int i = 0; i < q; ++i) {
      const double d = hellingerFromSqrt(&s.reference_sqrt_histograms[j * kHistogramBins],
                                         s.reference_histogram_empty[j] != 0,
                                         &s.query_sqrt_histograms[i * kHistogramBins], s.query_histogram_empty[i] != 0);
      const long cost = orderCost(j, i, m, q, previous_partner < 0 ? -1 : previous_partner + 1);
      if (d < best - kHistogramTie || (d <= best + kHistogramTie && cost < best_cost)) {
        best = std::min(best, d);
        best_letter = i;
        best_cost = cost;
      }
    }
    previous_partner = -1;
    if (best_letter >= 0 && best <= config_.max_hellinger_distance) {
      s.histogram_scores[static_cast<std::size_t>(j) * q + best_letter] = static_cast<float>(1.0 - best);
      previous_partner = best_letter;
    }
  }
}

int NgramMatcher::matchKeypoints(const Fingerprint& reference, const Fingerprint& query, MatchScratch& s,
                                 ReversePass reverse) const {
  const bool take_reverse = reverse == ReversePass::Take && s.reverse_ready;
  s.reverse_ready = false;  // a kept reverse serves the very next call only
  const int m = static_cast<int>(reference.subregions.size());
  const int q = static_cast<int>(query.subregions.size());
  const std::size_t cells = static_cast<std::size_t>(m) * static_cast<std::size_t>(q);
  resizeFor(s.keypoint_scores, cells, 0.f);
  if (m == 0 || q == 0 || !hasDescriptors(reference) || !hasDescriptors(query)) return 0;
  const cv::Mat& rd = reference.descriptors;
  const cv::Mat& qd = query.descriptors;
  if (rd.type() != qd.type() || rd.cols != qd.cols) return 0;  // different backends: nothing comparable

  resizeFor(s.matches, static_cast<std::size_t>(qd.rows), DescriptorMatch{});
  const bool mutual = config_.mutual_check;
  if (mutual) resizeFor(s.reference_best, static_cast<std::size_t>(rd.rows), -1);
  double max_distance = std::numeric_limits<double>::infinity();
  if (rd.depth() == CV_8U) {
    const int words = (rd.cols + 7) / 8;
    if (take_reverse) {
      // The previous call matched (reference = this query, query = this reference) and kept both ways.
      std::swap(s.reference_words, s.query_words);
      s.matches.swap(s.reverse_matches);
      if (mutual) s.reference_best.swap(s.reverse_reference_best);
    } else if (reverse == ReversePass::Keep) {
      packBinaryRows(rd, words, s.reference_words);
      packBinaryRows(qd, words, s.query_words);
      resizeFor(s.reference_best, static_cast<std::size_t>(rd.rows), -1);
      resizeFor(s.reference_best_bits, static_cast<std::size_t>(rd.rows), 0);
      resizeFor(s.reference_second_bits, static_cast<std::size_t>(rd.rows), 0);
      resizeFor(s.reverse_matches, static_cast<std::size_t>(rd.rows), DescriptorMatch{});
      detail::bestBinaryMatchesBothWays(s.query_words.data(), qd.rows, s.reference_words.data(), rd.rows, words,
                                        s.matches.data(), s.reverse_matches.data(), s.reference_best.data(),
                                        s.reference_best_bits.data(), s.reference_second_bits.data());
      resizeFor(s.reverse_reference_best, static_cast<std::size_t>(qd.rows), -1);
      for (int k = 0; k < qd.rows; ++k) s.reverse_reference_best[k] = s.matches[k].reference_keypoint;
      s.reverse_ready = true;
    } else {
      packBinaryRows(rd, words, s.reference_words);
      packBinaryRows(qd, words, s.query_words);
      if (mutual) resizeFor(s.reference_best_bits, static_cast<std::size_t>(rd.rows), 0);
      detail::bestBinaryMatches(s.query_words.data(), qd.rows, s.reference_words.data(), rd.rows, words,
                                s.matches.data(), mutual ? s.reference_best.data() : nullptr,
                                mutual ? s.reference_best_bits.data() : nullptr);
    }
    if (config_.max_binary_distance_fraction < 1.0) max_distance = config_.max_binary_distance_fraction * 8.0 * rd.cols;
  } else {
    // cv::Mat rows may be padded: pass strides in floats (step is a multiple of 4 for CV_32F).
    const int query_stride = static_cast<int>(qd.step1());
    const int reference_stride = static_cast<int>(rd.step1());
    if (mutual) resizeFor(s.reference_best_l2, static_cast<std::size_t>(rd.rows), 0.f);
    detail::bestFloatMatches(qd.ptr<float>(0), qd.rows, query_stride, rd.ptr<float>(0), rd.rows,
                             reference_stride, rd.cols, s.matches.data(), mutual ? s.reference_best.data() : nullptr,
                             mutual ? s.reference_best_l2.data() : nullptr);
    if (config_.max_float_distance > 0.0) max_distance = config_.max_float_distance;
  }

  resizeFor(s.reference_letter_of_keypoint, static_cast<std::size_t>(rd.rows), -1);
  for (int j = 0; j < m; ++j) {
    int begin = 0;
    int end = 0;
    keypointRange(reference.subregions[j], rd.rows, begin, end);
    for (int k = begin; k < end; ++k) s.reference_letter_of_keypoint[k] = j;
  }
  resizeFor(s.last_query_letter, static_cast<std::size_t>(rd.rows), -1);
  resizeFor(s.pair_matches, cells, 0);

  // Distance of query keypoint k to reference keypoint r, in the kernel's units (ties only: not hot).
  const auto distance = [&](int k, int r) -> float {
    if (rd.depth() == CV_8U) {
      const int words = (rd.cols + 7) / 8;
      const std::uint64_t* a = s.query_words.data() + static_cast<std::ptrdiff_t>(k) * words;
      const std::uint64_t* b = s.reference_words.data() + static_cast<std::ptrdiff_t>(r) * words;
      int bits = 0;
      for (int w = 0; w < words; ++w) bits += std::popcount(a[w] ^ b[w]);
      return static_cast<float>(bits);
    }
    const float* a = qd.ptr<float>(k);
    const float* b = rd.ptr<float>(r);
    float squared = 0.f;
    for (int c = 0; c < rd.cols; ++c) squared += (a[c] - b[c]) * (a[c] - b[c]);
    return std::sqrt(squared);
  };
  // Orientation check (0 = off). Keypoints without an orientation (angle < 0) always pass.
  const double max_angle = config_.max_angle_difference_deg;
  const bool check_angles = max_angle > 0.0 && max_angle < 180.0 &&
                            reference.keypoints.size() == static_cast<std::size_t>(rd.rows) &&
                            query.keypoints.size() == static_cast<std::size_t>(qd.rows);
  const auto anglesAgree = [&](int k, int r) {
    if (!check_angles) return true;
    const float a = query.keypoints[static_cast<std::size_t>(k)].angle;
    const float b = reference.keypoints[static_cast<std::size_t>(r)].angle;
    if (a < 0.f || b < 0.f) return true;
    double d = std::fabs(static_cast<double>(a) - static_cast<double>(b));
    d = std::fmod(d, 360.0);
    return std::min(d, 360.0 - d) <= max_angle;
  };
  // Keeps a match that passed the tests: each reference keypoint counts once per letter pair.
  int kept = 0;
  const auto keep = [&](int r, int i) {
    ++kept;
    const int j = s.reference_letter_of_keypoint[r];
    if (j < 0 || s.last_query_letter[r] == i) return;
    s.last_query_letter[r] = i;
    ++s.pair_matches[static_cast<std::size_t>(j) * q + i];
  };
  // The reference letter query letter i matched most (ties: the earlier), -1 if none.
  const auto partnerOf = [&](int i) {
    int partner = -1;
    int most = 0;
    for (int j = 0; j < m; ++j) {
      const int count = s.pair_matches[static_cast<std::size_t>(j) * q + i];
      if (count > most) {
        most = count;
        partner = j;
      }
    }
    return partner;
  };

  int previous_partner = -1;
  for (int i = 0; i < q; ++i) {
    int begin = 0;
    int end = 0;
    keypointRange(query.subregions[i], qd.rows, begin, end);
    // Pass 1: unambiguous best matches. A best distance shared by several reference keypoints
    // (second == best) waits for pass 2.
    for (int k = begin; k < end; ++k) {
      const DescriptorMatch& match = s.matches[k];
      if (match.reference_keypoint < 0 || match.second_distance == match.distance) continue;
      if (!(match.distance <= max_distance)) continue;
      if (config_.ratio_test < 1.0 &&
          !(static_cast<double>(match.distance) <= config_.ratio_test * match.second_distance))
        continue;
      if (mutual && s.reference_best[match.reference_keypoint] != k) continue;
      if (!anglesAgree(k, match.reference_keypoint)) continue;
      keep(match.reference_keypoint, i);
    }
    // Pass 2: equally good candidates resolve to the order-consistent one: in the reference letter this
    // query letter already matched, else the one after the previous query letter's partner, else the same
    // relative position; within that letter, the keypoint at the same offset. The tests are unchanged:
    // a tie fails the ratio test unless its distance is 0 (duplicated descriptors) or the test is off.
    const int own_partner = partnerOf(i);
    const int preferred = own_partner >= 0 ? own_partner : previous_partner >= 0 ? previous_partner + 1 : -1;
    for (int k = begin; k < end; ++k) {
      const DescriptorMatch& match = s.matches[k];
      if (match.reference_keypoint < 0 || match.second_distance != match.distance) continue;
      if (!(match.distance <= max_distance)) continue;
      if (config_.ratio_test < 1.0 &&
          !(static_cast<double>(match.distance) <= config_.ratio_test * match.second_distance))
        continue;
      int chosen = -1;
      long chosen_letter_cost = 0;
      int chosen_offset_cost = 0;
      for (int r = 0; r < rd.rows; ++r) {
        if (distance(k, r) != match.distance) continue;
        const int j = s.reference_letter_of_keypoint[r];
        const long letter_cost = j < 0 ? std::numeric_limits<long>::max() : orderCost(i, j, q, m, preferred);
        const int offset_cost =
            j < 0 ? 0 : std::abs((r - reference.subregions[j].keypoint_begin) - (k - begin));
        if (chosen < 0 || letter_cost < chosen_letter_cost ||
            (letter_cost == chosen_letter_cost && offset_cost < chosen_offset_cost)) {
          chosen = r;
          chosen_letter_cost = letter_cost;
          chosen_offset_cost = offset_cost;
        }
      }
      // Mutual check on ties: the chosen reference keypoint's best query keypoint must be as close.
      if (mutual && (chosen < 0 || s.reference_best[chosen] < 0 ||
                     distance(s.reference_best[chosen], chosen) != match.distance))
        continue;
      if (chosen >= 0 && !anglesAgree(k, chosen)) continue;
      keep(chosen, i);
    }
    previous_partner = partnerOf(i);
  }
  for (int j = 0; j < m; ++j) {
    const int own = reference.subregions[j].keypointCount();
    if (own <= 0) continue;
    for (int i = 0; i < q; ++i) {
      const int matched = s.pair_matches[static_cast<std::size_t>(j) * q + i];
      if (matched > 0) {
        s.keypoint_scores[static_cast<std::size_t>(j) * q + i] =
            static_cast<float>(std::min(1.0, static_cast<double>(matched) / own));
      }
    }
  }
  return kept;
}

void NgramMatcher::verifiedMatchCounts(int m, int q, MatchScratch& s, NgramCounts& result) {
  const auto cell = [q](int j, int i) { return static_cast<std::size_t>(j) * static_cast<std::size_t>(q) + i; };
  // Matches per order: a cell counts for order n when some complete diagonal run of n non-empty cells
  // passes through it.
  for (int n = 1; n <= kMaxNgramOrder; ++n) {
    int total = 0;
    for (int j = 0; j < m; ++j) {
      for (int i = 0; i < q; ++i) {
        const int matched = s.pair_matches[cell(j, i)];
        if (matched <= 0) continue;
        bool on_ngram = n == 1;
        for (int start = 0; start < n && !on_ngram; ++start) {  // run covers offsets -start .. n-1-start
          const int j0 = j - start;
          const int i0 = i - start;
          if (j0 < 0 || i0 < 0 || j0 + n > m || i0 + n > q) continue;
          bool complete = true;
          for (int t = 0; t < n && complete; ++t) complete = s.pair_matches[cell(j0 + t, i0 + t)] > 0;
          on_ngram = complete;
        }
        if (on_ngram) total += matched;
      }
    }
    result.keypoint_ngram_matches[n - 1] = total;
  }
  // Order-preserving alignment: best[j][i] = most matches on a monotone staircase of cells (reference
  // and query letters both non-decreasing) ending at (j, i). Non-decreasing rather than strictly
  // increasing, so a letter split in two by an edge seen in only one of the frames keeps both halves.
  resizeFor(s.alignment, static_cast<std::size_t>(m) * static_cast<std::size_t>(q), 0);
  int overall = 0;
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < q; ++i) {
      int previous = 0;
      if (j > 0) previous = std::max(previous, s.alignment[cell(j - 1, i)]);
      if (i > 0) previous = std::max(previous, s.alignment[cell(j, i - 1)]);
      if (j > 0 && i > 0) previous = std::max(previous, s.alignment[cell(j - 1, i - 1)]);
      s.alignment[cell(j, i)] = previous + s.pair_matches[cell(j, i)];
      overall = std::max(overall, s.alignment[cell(j, i)]);
    }
  }
  result.aligned_matches = overall;
}

NgramCounts NgramMatcher::counts(const Fingerprint& reference, const Fingerprint& query,
                                 MatchScratch* scratch) const {
  return countsWith(reference, query, scratch != nullptr ? *scratch : threadScratch(), ReversePass::None);
}

std::pair<NgramCounts, NgramCounts> NgramMatcher::countsBothWays(const Fingerprint& a, const Fingerprint& b,
                                                                 MatchScratch* scratch) const {
  MatchScratch& s = scratch != nullptr ? *scratch : threadScratch();
  NgramCounts forward = countsWith(a, b, s, ReversePass::Keep);
  NgramCounts backward = countsWith(b, a, s, ReversePass::Take);
  return {std::move(forward), std::move(backward)};
}

NgramCounts NgramMatcher::countsWith(const Fingerprint& reference, const Fingerprint& query, MatchScratch& s,
                                     ReversePass reverse) const {
  NgramCounts result;
  const int m = static_cast<int>(reference.subregions.size());
  const int q = static_cast<int>(query.subregions.size());
  result.query_keypoints = hasDescriptors(query) ? query.descriptors.rows : 0;

  matchHistograms(reference, query, s);
  result.matched_keypoints = matchKeypoints(reference, query, s, reverse);

  const bool reference_has_keypoints = hasDescriptors(reference);
  result.reference_keypoints = reference_has_keypoints ? reference.descriptors.rows : 0;
  result.query_letters = q;
  if (m > 0 && q > 0 && result.matched_keypoints > 0) verifiedMatchCounts(m, q, s, result);
  for (int n = 1; n <= kMaxNgramOrder; ++n) {
    result.histogram_possible[n - 1] = std::max(0, m - n + 1);
    // Keypoint n-grams are only possible over reference letters that own keypoints.
    int possible = 0;
    int run = 0;
    for (int j = 0; j < m && reference_has_keypoints; ++j) {
      run = reference.subregions[j].keypointCount() > 0 ? run + 1 : 0;
      if (run >= n) ++possible;
    }
    result.keypoint_possible[n - 1] = possible;
    if (m == 0 || q == 0) continue;
    result.histogram[n - 1] = countNgrams(s.histogram_scores.data(), m, q, n, &result.histogram_matched[n - 1]);
    result.keypoint[n - 1] = countNgrams(s.keypoint_scores.data(), m, q, n, &result.keypoint_matched[n - 1]);
  }
  return result;
}

LetterCorrespondences NgramMatcher::correspondences(const Fingerprint& reference,
                                                    const Fingerprint& query) const {
  MatchScratch s;
  matchHistograms(reference, query, s);
  matchKeypoints(reference, query, s);
  LetterCorrespondences result;
  const int m = static_cast<int>(reference.subregions.size());
  const int q = static_cast<int>(query.subregions.size());
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < q; ++i) {
      const std::size_t cell = static_cast<std::size_t>(j) * q + i;
      if (s.histogram_scores[cell] > 0.f) result.histogram.push_back({j, i, s.histogram_scores[cell], 0});
      if (s.keypoint_scores[cell] > 0.f)
        result.keypoint.push_back({j, i, s.keypoint_scores[cell], s.pair_matches[cell]});
    }
  }
  return result;
}

}  // namespace toposlam
