// Structural vertical edges (thesis section 3.2.1) and the 1-D non-maximum suppression of
// Algorithm 3.1 (Neubeck and Van Gool's (2n+1)-neighbourhood NMS, adapted to keep maxima near the ends).
#include "toposlam/fingerprint/vertical_edge_detector.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

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
  const int height = grey.rows;
  result.column_response.clear();
  result.threshold = 0.f;
  result.columns.clear();

  // Three working images, reused from frame to frame: the signed gradient and two 8-bit planes the
  // morphology below goes back and forth between.
  // 1. |Sobel x|, saturated to 8 bits (the morphology below is fastest on 8-bit data).
  cv::Sobel(grey, scratch.gradient, CV_16S, 1, 0, 3);
  cv::convertScaleAbs(scratch.gradient, scratch.plane_a);
  // 2. Horizontal dilation rejoins edges cut by a little roll or a sloping floor.
  if (scratch.dilation_kernel.cols != config_.dilation_width)
    scratch.dilation_kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(config_.dilation_width, 1));
  cv::dilate(scratch.plane_a, scratch.plane_b, scratch.dilation_kernel);
  // 3. Vertical opening (erosion, then dilation) removes segments shorter than a fifth of the height.
  const int opening = std::clamp(static_cast<int>(std::lround(config_.opening_height_fraction * height)), 1,
                                 height);
  if (scratch.opening_kernel.rows != opening)
    scratch.opening_kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(1, opening));
  cv::erode(scratch.plane_b, scratch.plane_a, scratch.opening_kernel);
  cv::dilate(scratch.plane_a, scratch.plane_b, scratch.opening_kernel);
  // 4. Column response, normalised to a maximum of 1 (the sums are whole numbers below 2^24: exact).
  cv::reduce(scratch.plane_b, scratch.column_sums, 0, cv::REDUCE_SUM, CV_32F);
  result.column_response.assign(scratch.column_sums.ptr<float>(0), scratch.column_sums.ptr<float>(0) + width);
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
