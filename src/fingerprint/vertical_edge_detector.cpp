// Structural vertical edges (thesis section 3.2.1) and the 1-D non-maximum suppression of
// Algorithm 3.1 (Neubeck and Van Gool's (2n+1)-neighbourhood NMS, adapted to keep maxima near the ends).
#include "toposlam/fingerprint/vertical_edge_detector.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace toposlam {

std::string VerticalEdgeConfig::validate() const {
  std::ostringstream e;
  if (!(opening_height_fraction > 0.0 && opening_height_fraction <= 1.0))
    e << "fingerprint.edges.opening_height_fraction: " << opening_height_fraction << " is outside (0, 1]";
  else if (dilation_width < 1 || dilation_width > 31)
    e << "fingerprint.edges.dilation_width: " << dilation_width << " is outside [1, 31]";
  else if (!(mean_factor > 0.0 && mean_factor <= 100.0))
    e << "fingerprint.edges.mean_factor: " << mean_factor << " is outside (0, 100]";
  else if (!(min_separation_fraction > 0.0 && min_separation_fraction <= 0.5))
    e << "fingerprint.edges.min_separation_fraction: " << min_separation_fraction << " is outside (0, 0.5]";
  return e.str();
}

VerticalEdgeDetector::VerticalEdgeDetector(const VerticalEdgeConfig& config) : config_(config) {
  if (std::string problem = config_.validate(); !problem.empty()) throw std::invalid_argument(problem);
}

namespace {

/// OpenCV's BORDER_REFLECT_101 (the Sobel filter's default border): -1 -> 1, n -> n - 2.
int reflect101(int i, int n) {
  if (n == 1) return 0;
  if (i < 0) return -i;
  if (i >= n) return 2 * n - 2 - i;
  return i;
}

/// One opening pass along the columns (a window of `k` rows, anchor k / 2, rows outside ignored) over
/// `rows` rows of `width` bytes: the minimum (erosion) or maximum (dilation) of each window, by van
/// Herk and Gil-Werman's running extrema per block of k rows (three operations per pixel for any k).
/// `prefix` and `suffix` hold (rows + k - 1) rows. `out_row(y, suffix_row, prefix_row)` gets row y of the
/// result as the two rows whose pixelwise extreme it is.
template <bool kMinimum, typename Out>
void columnExtrema(const std::uint8_t* in, int rows, int width, int k, std::vector<std::uint8_t>& prefix,
                   std::vector<std::uint8_t>& suffix, std::vector<std::uint8_t>& identity_row,
                   Out&& out_row) {
  const int anchor = k / 2;
  const int padded = rows + k - 1;
  const auto w = static_cast<std::size_t>(width);
  prefix.resize(static_cast<std::size_t>(padded) * w);
  suffix.resize(static_cast<std::size_t>(padded) * w);
  identity_row.assign(w, kMinimum ? 255 : 0);
  auto source = [&](int i) {  // row i of the input padded with identity rows: input row i - anchor
    const int r = i - anchor;
    return (r >= 0 && r < rows) ? in + static_cast<std::size_t>(r) * w : identity_row.data();
  };
  auto pick = [](std::uint8_t a, std::uint8_t b) { return kMinimum ? std::min(a, b) : std::max(a, b); };
  for (int block = 0; block < padded; block += k) {
    const int end = std::min(block + k, padded);
    std::uint8_t* g = prefix.data() + static_cast<std::size_t>(block) * w;
    std::copy_n(source(block), w, g);
    for (int i = block + 1; i < end; ++i) {
      const std::uint8_t* p = source(i);
      const std::uint8_t* previous = prefix.data() + static_cast<std::size_t>(i - 1) * w;
      std::uint8_t* current = prefix.data() + static_cast<std::size_t>(i) * w;
      for (std::size_t x = 0; x < w; ++x) current[x] = pick(previous[x], p[x]);
    }
    std::uint8_t* h = suffix.data() + static_cast<std::size_t>(end - 1) * w;
    std::copy_n(source(end - 1), w, h);
    for (int i = end - 2; i >= block; --i) {
      const std::uint8_t* p = source(i);
      const std::uint8_t* next = suffix.data() + static_cast<std::size_t>(i + 1) * w;
      std::uint8_t* current = suffix.data() + static_cast<std::size_t>(i) * w;
      for (std::size_t x = 0; x < w; ++x) current[x] = pick(next[x], p[x]);
    }
  }
  // Window [y, y + k - 1] of the padded rows = suffix extreme from y to its block's end, and prefix
  // extreme from the next block's start to y + k - 1 (one of them covers it all at a block start).
  for (int y = 0; y < rows; ++y) {
    const std::uint8_t* h = suffix.data() + static_cast<std::size_t>(y) * w;
    const std::uint8_t* g = prefix.data() + static_cast<std::size_t>(y + k - 1) * w;
    out_row(y, h, g);
  }
}

}  // namespace

void VerticalEdgeDetector::columnResponse(const cv::Mat& grey, VerticalEdgeScratch& scratch) const {
  const int width = grey.cols;
  const int height = grey.rows;
  const auto w = static_cast<std::size_t>(width);
  // 1. |Sobel x| ([-1 0 1] across, [1 2 1] down, borders reflected), saturated to 8 bits, and
  // 2. dilated across by dilation_width columns (anchor at its middle; columns outside are ignored),
  // which rejoins edges cut by a little roll or a sloping floor.
  scratch.magnitude.resize(w);
  scratch.dilated.resize(static_cast<std::size_t>(height) * w);
  const int across = config_.dilation_width;
  const int left = across / 2;
  // As OpenCV's filters do, a view into a larger image takes its neighbours beyond the view from that
  // image, and only the larger image's own border is reflected.
  cv::Size whole;
  cv::Point offset;
  grey.locateROI(whole, offset);
  auto row = [&](int y) {  // may lie outside the view, never outside the larger image
    const int in_whole = reflect101(offset.y + y, whole.height);
    return grey.data +
           static_cast<std::ptrdiff_t>(in_whole - offset.y) * static_cast<std::ptrdiff_t>(grey.step);
  };
  for (int y = 0; y < height; ++y) {
    const std::uint8_t* up = row(y - 1);
    const std::uint8_t* mid = row(y);
    const std::uint8_t* down = row(y + 1);
    std::uint8_t* m = scratch.magnitude.data();
    auto gradient_at = [&](int x) {
      const int l = reflect101(offset.x + x - 1, whole.width) - offset.x;
      const int r = reflect101(offset.x + x + 1, whole.width) - offset.x;
      const int g = (up[r] - up[l]) + 2 * (mid[r] - mid[l]) + (down[r] - down[l]);
      return static_cast<std::uint8_t>(std::min(255, g < 0 ? -g : g));
    };
    m[0] = gradient_at(0);
    m[w - 1] = gradient_at(width - 1);
    for (std::size_t x = 1; x + 1 < w; ++x) {
      const int g = (up[x + 1] - up[x - 1]) + 2 * (mid[x + 1] - mid[x - 1]) + (down[x + 1] - down[x - 1]);
      m[x] = static_cast<std::uint8_t>(std::min(255, g < 0 ? -g : g));
    }
    std::uint8_t* d = scratch.dilated.data() + static_cast<std::size_t>(y) * w;
    if (across == 3) {
      d[0] = width > 1 ? std::max(m[0], m[1]) : m[0];
      for (std::size_t x = 1; x + 1 < w; ++x) d[x] = std::max(m[x - 1], std::max(m[x], m[x + 1]));
      if (width > 1) d[w - 1] = std::max(m[w - 2], m[w - 1]);
    } else {
      for (int x = 0; x < width; ++x) {
        const int from = std::max(0, x - left), to = std::min(width - 1, x - left + across - 1);
        std::uint8_t v = 0;
        for (int i = from; i <= to; ++i) v = std::max(v, m[i]);
        d[x] = v;
      }
    }
  }
  // 3. Vertical opening (erosion, then dilation, over `opening` rows) removes segments shorter than a
  // fifth of the height; 4. the column sums of what remains.
  const int opening =
      std::clamp(static_cast<int>(std::lround(config_.opening_height_fraction * height)), 1, height);
  scratch.eroded.resize(static_cast<std::size_t>(height) * w);
  columnExtrema<true>(scratch.dilated.data(), height, width, opening, scratch.prefix, scratch.suffix,
                      scratch.identity_row, [&](int y, const std::uint8_t* h, const std::uint8_t* g) {
                        std::uint8_t* e = scratch.eroded.data() + static_cast<std::size_t>(y) * w;
                        for (std::size_t x = 0; x < w; ++x) e[x] = std::min(h[x], g[x]);
                      });
  scratch.sums.assign(w, 0);
  columnExtrema<false>(scratch.eroded.data(), height, width, opening, scratch.prefix, scratch.suffix,
                       scratch.identity_row, [&](int, const std::uint8_t* h, const std::uint8_t* g) {
                         std::uint32_t* sum = scratch.sums.data();
                         for (std::size_t x = 0; x < w; ++x) sum[x] += std::max(h[x], g[x]);
                       });
}

VerticalEdges VerticalEdgeDetector::detect(const cv::Mat& grey) const {
  VerticalEdgeScratch scratch;
  VerticalEdges result;
  detect(grey, result, scratch);
  return result;
}

void VerticalEdgeDetector::detect(const cv::Mat& grey, VerticalEdges& result,
                                  VerticalEdgeScratch& scratch) const {
  if (grey.empty()) throw std::invalid_argument("vertical edges: empty image");
  if (grey.type() != CV_8UC1) throw std::invalid_argument("vertical edges: expected an 8-bit grey image");
  const int width = grey.cols;
  result.column_response.clear();
  result.threshold = 0.f;
  result.columns.clear();

  // Steps 1-4 in our own loops, to the bit what OpenCV's Sobel, dilate, erode and reduce give (the
  // unit tests compare them), in buffers kept between frames and without OpenCV's per-call buffers.
  columnResponse(grey, scratch);
  result.column_response.resize(static_cast<std::size_t>(width));
  for (int x = 0; x < width; ++x)
    result.column_response[static_cast<std::size_t>(x)] =
        static_cast<float>(scratch.sums[static_cast<std::size_t>(x)]);
  const float peak = *std::max_element(result.column_response.begin(), result.column_response.end());
  if (peak <= 0.f) return;  // no structure at all: no edges
  double total = 0.0;
  for (float& v : result.column_response) {
    v /= peak;
    total += v;
  }
  // 5. Keep columns above mean_factor x the mean.
  result.threshold = static_cast<float>(config_.mean_factor * total / width);
  scratch.kept.assign(result.column_response.begin(), result.column_response.end());
  for (float& v : scratch.kept)
    if (v <= result.threshold) v = 0.f;
  // 6. Minimum separation between edges.
  const int half_width = std::max(1, static_cast<int>(std::lround(config_.min_separation_fraction * width)));
  result.columns = nonMaximumSuppression1d(scratch.kept, half_width);
}

// ---------------------------------------------------------------------------------------------------
// Algorithm 3.1: Neubeck and Van Gool's (2n+1)-neighbourhood NMS, which looks at each value about
// once. The original skips the n values at each end; the thesis adapts it so maxima near the borders
// count. We do that by running the original on the sequence padded with n values of -infinity at both
// ends, so a border value only has to beat its real neighbours.
namespace {

class PaddedSequence {
 public:
  PaddedSequence(const std::vector<float>& h, int n)
      : values_(h.size() + 2 * static_cast<std::size_t>(n), -std::numeric_limits<float>::infinity()),
        pmax_(values_.size(), 0.f) {
    std::copy(h.begin(), h.end(), values_.begin() + n);
  }
  int size() const { return static_cast<int>(values_.size()); }
  float operator[](int i) const { return values_[i]; }
  float pmax(int i) const { return pmax_[i]; }
  // ComputePartialMax: index of the maximum of [from, to] (the rightmost of equal values), and
  // pmax[x] = max(values[x..to]) for x in [from, to].
  int partialMax(int from, int to) {
    pmax_[to] = values_[to];
    int best = to;
    while (to > from) {
      --to;
      if (values_[to] <= values_[best]) {
        pmax_[to] = values_[best];
      } else {
        pmax_[to] = values_[to];
        best = to;
      }
    }
    return best;
  }

 private:
  std::vector<float> values_;
  std::vector<float> pmax_;
};

}  // namespace

std::vector<int> nonMaximumSuppression1d(const std::vector<float>& h, int n) {
  std::vector<int> maxima;
  if (h.empty() || n < 1) return maxima;
  PaddedSequence v(h, n);
  const int width = v.size();
  int i = n;
  int chkpt = -1;
  while (i < width - n) {
    const int j = v.partialMax(i, i + n);
    const int k = v.partialMax(i + n + 1, j + n);
    if (i == j || v[j] > v[k]) {
      if ((chkpt <= j - n || v[j] >= v.pmax(chkpt)) && (j - n == i || v[j] >= v.pmax(j - n)))
        maxima.push_back(j - n);  // back to unpadded indices
      if (i < j) chkpt = i + n + 1;
      i = j + n + 1;
    } else {
      i = k;
      chkpt = j + n + 1;
    }
  }
  // Values <= 0 are never maxima (they are the columns below the threshold).
  std::erase_if(maxima, [&](int m) { return h[m] <= 0.f; });
  return maxima;
}

}  // namespace toposlam
