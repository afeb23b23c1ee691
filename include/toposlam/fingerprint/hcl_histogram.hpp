// The 13-bin HCL colour histogram of one subregion (thesis section 3.2.2). Chroma = max - min of RGB in
// [0, 1]; chroma <= 0.125 is achromatic. Chromatic pixels vote into a 256-level hue histogram folded
// into 8 circular bins with triangular (fuzzy) membership; achromatic pixels vote by lightness
// (max + min) / 2 into 5 grey bins with triangular, non-circular membership. Stacked and normalised.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "toposlam/fingerprint/fingerprint.hpp"

namespace toposlam {

struct HclHistogramConfig {
  double achromatic_chroma = 0.125;  ///< chroma at or below this is grey (thesis: 12.5 %)
  /// Drop the bicone's apexes: ignore pixels darker than / brighter than these lightness values
  /// (0 and 1 keep everything, the thesis default; e.g. 0.05 and 0.95 for badly exposed cameras).
  double min_lightness = 0.0;
  double max_lightness = 1.0;
  std::string validate() const;
};

class HclHistogram {
 public:
  explicit HclHistogram(const HclHistogramConfig& config = {});
  /// bgr: CV_8UC3 image (OpenCV's BGR order); the histogram of the columns [column_begin, column_end).
  HclHistogramBins compute(const cv::Mat& bgr, int column_begin, int column_end) const;
  /// grey: CV_8UC1 image; equals compute() on the BGR image whose three channels are `grey`, without
  /// making it (a grey camera's frames are never turned into colour).
  HclHistogramBins computeGrey(const cv::Mat& grey, int column_begin, int column_end) const;
  /// Hue of one pixel on the 256-level scale (0 = red, 85.3 = green, 170.7 = blue).
  static double hueLevel(int r, int g, int b);

 private:
  HclHistogramConfig config_;
  int achromatic_max_difference_;  ///< max - min (0..255) at or below which a pixel is grey
  int min_lightness_sum_;          ///< on the (max + min) scale 0..510
  int max_lightness_sum_;
};

}  // namespace toposlam
