// A few robust keypoints per frame (thesis section 3.2.3): at most `max_keypoints` in the whole frame,
// spread over the subregions in proportion to their width. The detector runs once over the whole frame
// at a low response floor; each subregion then raises its own response threshold iteratively until it
// keeps no more than its share (re-detecting with a higher threshold keeps exactly the keypoints whose
// response is above it, so this is the thesis' iterative adjustment without re-running the detector).
// If more remain after `threshold_iterations`, all are kept, as in the thesis. Descriptors are computed
// on the whole frame, so a keypoint near a subregion border keeps its descriptor.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "toposlam/fingerprint/fingerprint.hpp"

namespace toposlam {

struct KeypointConfig {
  KeypointBackend backend = KeypointBackend::Orb;
  int max_keypoints = 100;          ///< per frame (thesis: 100)
  int threshold_iterations = 8;     ///< response threshold adjustments per subregion
  int candidate_limit = 1000;       ///< detector's own cap on candidates before selection
  int orb_levels = 4;               ///< ORB pyramid levels (fewer is faster)
  int orb_fast_threshold = 12;      ///< ORB FAST floor; low so the subregions have candidates to choose from
  std::string validate() const;
  /// Sets the per-frame budget and raises candidate_limit to it where lower (validate() wants
  /// candidate_limit >= max_keypoints): what every "--max-keypoints N" override means.
  void setMaxKeypoints(int budget) {
    max_keypoints = budget;
    if (candidate_limit < budget) candidate_limit = budget;
  }
};

/// Candidates found once per frame, before the per-subregion selection.
struct KeypointCandidates {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  ///< one row per candidate
};

class KeypointExtractor {
 public:
  explicit KeypointExtractor(const KeypointConfig& config = {});
  KeypointBackend backend() const { return config_.backend; }
  const KeypointConfig& config() const { return config_; }

  /// A detector for this config. Reused from frame to frame by one caller at a time (OpenCV's
  /// detectors are not documented as safe to share between threads).
  cv::Ptr<cv::Feature2D> createDetector() const;
  /// Detects and describes candidates over the whole grey frame (CV_8UC1), with a detector of its own.
  KeypointCandidates detect(const cv::Mat& grey) const;
  /// The same with `detector` (from createDetector()), into `out`, whose storage is reused.
  void detect(cv::Feature2D& detector, const cv::Mat& grey, KeypointCandidates& out) const;
  /// Indices into `candidates` of the keypoints the subregion [column_begin, column_end) keeps,
  /// at most `budget` unless the threshold iterations could not get there; strongest first.
  std::vector<int> select(const KeypointCandidates& candidates, int column_begin, int column_end,
                          int budget) const;
  /// Splits max_keypoints over subregions in proportion to their width (sums to max_keypoints).
  std::vector<int> budgets(const std::vector<Subregion>& subregions, int image_width) const;

 private:
  KeypointConfig config_;
};

}  // namespace toposlam
