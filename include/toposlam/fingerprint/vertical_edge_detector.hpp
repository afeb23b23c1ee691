// Structural vertical edges (thesis section 3.2.1, Algorithm 3.2 steps 1-6): grey image, |Sobel x|,
// 3x1 horizontal dilation, vertical opening of a fraction of the height (1/5), column response,
// keep columns above 5 x the mean response, then the 1-D non-maximum suppression of Algorithm 3.1 with a
// minimum separation of 5 % of the width. n edges split the frame into n+1 ordered subregions.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace toposlam {

struct VerticalEdgeConfig {
  double opening_height_fraction = 0.2;  ///< vertical opening kernel = this x image height (thesis: 1/5)
  int dilation_width = 3;                ///< horizontal dilation kernel width in pixels (thesis: 3)
  double mean_factor = 5.0;              ///< keep columns whose response exceeds this x the mean (thesis: 5)
  double min_separation_fraction = 0.05; ///< NMS half-neighbourhood = this x image width (thesis: 5 %)
  /// Returns "" when valid, else "<key>: <problem and allowed range>".
  std::string validate() const;
};

/// Column response and the edges found in it, kept for drawing and diagnostics.
struct VerticalEdges {
  std::vector<float> column_response;  ///< per column, normalised so the maximum is 1 (all 0 if none)
  float threshold = 0.f;               ///< mean_factor x mean, on the same normalised scale
  std::vector<int> columns;            ///< edge columns, ascending
};

/// The working memory of one detection. Kept by a caller that detects frame after frame, so frames of
/// one size need no new memory; used by one detection at a time.
struct VerticalEdgeScratch {
  std::vector<std::uint8_t> magnitude;        ///< one row of |Sobel x|
  std::vector<std::uint8_t> dilated, eroded;  ///< height x width
  std::vector<std::uint8_t> prefix, suffix;   ///< the opening's running extrema, (height + k - 1) x width
  std::vector<std::uint8_t> identity_row;     ///< rows outside the image
  std::vector<std::uint32_t> sums;            ///< column sums of the opened image
  std::vector<float> kept;                    ///< the column response above the threshold
};

class VerticalEdgeDetector {
 public:
  explicit VerticalEdgeDetector(const VerticalEdgeConfig& config = {});
  /// grey: CV_8UC1 image. Throws std::invalid_argument on an empty or non-8-bit-grey image.
  VerticalEdges detect(const cv::Mat& grey) const;
  /// The same into `result`, working in `scratch` (both reused from frame to frame).
  void detect(const cv::Mat& grey, VerticalEdges& result, VerticalEdgeScratch& scratch) const;

 private:
  /// Steps 1-4 into scratch.sums.
  void columnResponse(const cv::Mat& grey, VerticalEdgeScratch& scratch) const;

  VerticalEdgeConfig config_;
};

/// Algorithm 3.1: indices of the maxima of `values` over a (2 * half_width + 1) neighbourhood,
/// counting maxima near both ends. For distinct values a maximum is strictly greater than every other
/// value within half_width of it (equal values: see the algorithm's tie rule in the source). Values <= 0
/// are never maxima.
std::vector<int> nonMaximumSuppression1d(const std::vector<float>& values, int half_width);

}  // namespace toposlam
