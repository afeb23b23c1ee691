// 13-bin HCL histogram with fuzzy voting (thesis section 3.2.2). Integer arithmetic per pixel: the hue
// on a 256-level circle via a fixed-point reciprocal table, the lightness as max + min on 0..510; the
// triangular memberships are applied once per subregion to the 256-level histograms (as in Figure 3.7).
#include "toposlam/fingerprint/hcl_histogram.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace toposlam {

std::string HclHistogramConfig::validate() const {
  std::ostringstream e;
  if (!(achromatic_chroma >= 0.0 && achromatic_chroma < 1.0))
    e << "fingerprint.histogram.achromatic_chroma: " << achromatic_chroma << " is outside [0, 1)";
  else if (!(min_lightness >= 0.0 && min_lightness < max_lightness && max_lightness <= 1.0))
    e << "fingerprint.histogram.min_lightness/max_lightness: need 0 <= min_lightness < max_lightness <= 1, got "
      << min_lightness << " and " << max_lightness;
  return e.str();
}

namespace {

constexpr int kFixedShift = 12;
constexpr int kFixedOne = 1 << kFixedShift;
constexpr int kLevels = 256;
constexpr int kLevelsPerHueBin = kLevels / kHueBins;  // 32

// hue_step[d] = (256 / 6) / d in fixed point: one sixth of the hue circle per unit of (g - b) / d.
const std::array<int, 256>& hueStepTable() {
  static const std::array<int, 256> table = [] {
    std::array<int, 256> t{};
    for (int d = 1; d < 256; ++d) t[d] = static_cast<int>(std::lround(kLevels / 6.0 * kFixedOne / d));
    return t;
  }();
  return table;
}

inline int hueLevelFixed(int r, int g, int b, int max, int diff, const std::array<int, 256>& step) {
  int numerator, base;
  if (max == r) {
    numerator = g - b;
    base = 0;
  } else if (max == g) {
    numerator = b - r;
    base = kLevels * kFixedOne / 3;
  } else {
    numerator = r - g;
    base = 2 * kLevels * kFixedOne / 3;
  }
  int level = (base + numerator * step[diff] + kFixedOne / 2) >> kFixedShift;
  if (level < 0) level += kLevels;
  if (level >= kLevels) level -= kLevels;
  return level;
}

}  // namespace

HclHistogram::HclHistogram(const HclHistogramConfig& config) : config_(config) {
  if (std::string problem = config_.validate(); !problem.empty()) throw std::invalid_argument(problem);
  achromatic_max_difference_ = static_cast<int>(std::floor(config_.achromatic_chroma * 255.0 + 1e-9));
  min_lightness_sum_ = static_cast<int>(std::ceil(config_.min_lightness * 510.0 - 1e-9));
  max_lightness_sum_ = static_cast<int>(std::floor(config_.max_lightness * 510.0 + 1e-9));
}

double HclHistogram::hueLevel(int r, int g, int b) {
  const int max = std::max({r, g, b});
  const int diff = max - std::min({r, g, b});
  if (diff == 0) return 0.0;
  return hueLevelFixed(r, g, b, max, diff, hueStepTable());
}

namespace {

/// Folds the 256-level hue and 511-level lightness counts into the 13 fuzzy bins, normalised.
HclHistogramBins foldLevels(const std::array<std::uint32_t, kLevels>& hue,
                            const std::array<std::uint32_t, 511>& lightness) {
  // Fold the 256 hue levels into 8 circular bins centred on levels 0, 32, ..., 224: each level votes
  // for its two nearest centres in proportion to its closeness (triangular membership).
  std::array<double, kHistogramBins> bins{};
  for (int level = 0; level < kLevels; ++level) {
    if (hue[level] == 0) continue;
    const int lower = level / kLevelsPerHueBin;
    const double upper_share = static_cast<double>(level % kLevelsPerHueBin) / kLevelsPerHueBin;
    bins[lower] += hue[level] * (1.0 - upper_share);
    bins[(lower + 1) % kHueBins] += hue[level] * upper_share;
  }
  // Grey: 5 centres on lightness 0, 0.25, 0.5, 0.75, 1 (not circular). Bin order white ... black, so
  // grey level g (0 = black, 4 = white) goes to bin kHueBins + 4 - g.
  for (int sum = 0; sum <= 510; ++sum) {
    if (lightness[sum] == 0) continue;
    const double position = sum / 127.5;  // 0..4
    const int lower = std::min(static_cast<int>(position), kGreyBins - 1);
    const double upper_share = position - lower;
    bins[kHueBins + (kGreyBins - 1) - lower] += lightness[sum] * (1.0 - upper_share);
    if (upper_share > 0.0) bins[kHueBins + (kGreyBins - 1) - (lower + 1)] += lightness[sum] * upper_share;
  }
  double total = 0.0;
  for (double v : bins) total += v;
  HclHistogramBins result{};
  if (total > 0.0)
    for (int i = 0; i < kHistogramBins; ++i) result[i] = static_cast<float>(bins[i] / total);
  return result;
}

}  // namespace

HclHistogramBins HclHistogram::compute(const cv::Mat& bgr, int column_begin, int column_end) const {
  if (bgr.type() != CV_8UC3) throw std::invalid_argument("HCL histogram: expected an 8-bit BGR image");
  column_begin = std::clamp(column_begin, 0, bgr.cols);
  column_end = std::clamp(column_end, column_begin, bgr.cols);
  std::array<std::uint32_t, kLevels> hue{};
  std::array<std::uint32_t, 511> lightness{};  // indexed by max + min
  const auto& step = hueStepTable();
  const int grey_limit = achromatic_max_difference_;
  const int lo = min_lightness_sum_, hi = max_lightness_sum_;
  const bool all_lightness = lo <= 0 && hi >= 510;

  for (int y = 0; y < bgr.rows; ++y) {
    const std::uint8_t* p = bgr.ptr<std::uint8_t>(y) + 3 * column_begin;
    const std::uint8_t* end = bgr.ptr<std::uint8_t>(y) + 3 * column_end;
    for (; p < end; p += 3) {
      const int b = p[0], g = p[1], r = p[2];
      const int max = std::max(r, std::max(g, b));
      const int min = std::min(r, std::min(g, b));
      const int sum = max + min;
      if (!all_lightness && (sum < lo || sum > hi)) continue;
      const int diff = max - min;
      if (diff <= grey_limit)
        ++lightness[sum];
      else
        ++hue[hueLevelFixed(r, g, b, max, diff, step)];
    }
  }
  return foldLevels(hue, lightness);
}

HclHistogramBins HclHistogram::computeGrey(const cv::Mat& grey, int column_begin, int column_end) const {
  if (grey.type() != CV_8UC1) throw std::invalid_argument("HCL histogram: expected an 8-bit grey image");
  column_begin = std::clamp(column_begin, 0, grey.cols);
  column_end = std::clamp(column_end, column_begin, grey.cols);
  // A grey pixel v is the BGR pixel (v, v, v): chroma 0, so always achromatic, lightness sum 2v. Count
  // the levels first, then vote, so this equals compute() on the BGR image made from `grey`.
  std::array<std::uint32_t, kLevels> level{};
  for (int y = 0; y < grey.rows; ++y) {
    const std::uint8_t* p = grey.ptr<std::uint8_t>(y);
    for (int x = column_begin; x < column_end; ++x) ++level[p[x]];
  }
  std::array<std::uint32_t, kLevels> hue{};
  std::array<std::uint32_t, 511> lightness{};
  for (int v = 0; v < kLevels; ++v) {
    const int sum = 2 * v;
    if (sum >= min_lightness_sum_ && sum <= max_lightness_sum_) lightness[sum] = level[v];
  }
  return foldLevels(hue, lightness);
}

}  // namespace toposlam
