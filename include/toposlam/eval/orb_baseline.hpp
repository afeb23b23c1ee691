// The plain baseline every place recognition figure is reported beside (docs/matching.md): OpenCV's ORB
// on the whole grey frame, brute-force Hamming matching both ways, Lowe's ratio test and a mutual
// check, similarity = good matches / the smaller keypoint count. No subregions, no colour, no order: what
// a robotics engineer would try first. Same keypoint budget as the fingerprint it is compared with.
//
// Thread-safety: extract() and similarity() are const and may be called concurrently.
#pragma once

#include <opencv2/core.hpp>

namespace toposlam::eval {

struct OrbBaselineConfig {
  int keypoints = 100;  ///< ORB's own cap (cv::ORB nfeatures)
  double ratio = 0.8;   ///< Lowe's ratio test, on both directions
};

class OrbBaseline {
 public:
  explicit OrbBaseline(const OrbBaselineConfig& config = {});
  /// Descriptors of one frame (BGR or grey, 8-bit); rows = keypoints, CV_8U, may be empty.
  cv::Mat extract(const cv::Mat& image) const;
  /// Mutual ratio-test matches / min(rows of a, rows of b), in [0, 1]; 0 when either is empty. Symmetric.
  double similarity(const cv::Mat& a, const cv::Mat& b) const;

 private:
  OrbBaselineConfig config_;
};

}  // namespace toposlam::eval
