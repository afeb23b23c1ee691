// VPACK extraction (thesis Algorithm 3.2): vertical edges split the frame into ordered subregions; each
// subregion gets its HCL histogram and its share of keypoints. The per-subregion work runs on the
// WorkerPool handed to the extractor (none = inline); results are identical for any pool size.
#pragma once

#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "toposlam/fingerprint/fingerprint.hpp"
#include "toposlam/fingerprint/hcl_histogram.hpp"
#include "toposlam/fingerprint/keypoint_extractor.hpp"
#include "toposlam/fingerprint/vertical_edge_detector.hpp"

namespace toposlam {

class WorkerPool;

struct VpackConfig {
  VerticalEdgeConfig edges;
  HclHistogramConfig histogram;
  KeypointConfig keypoints;
  int min_image_width = 16;   ///< smaller frames are refused (pixels)
  int min_image_height = 16;
  std::string validate() const;
};

/// What one extraction produced besides the fingerprint (for drawing and diagnostics).
struct VpackDiagnostics {
  VerticalEdges edges;
};

class VpackExtractor {
 public:
  /// Throws std::invalid_argument naming the bad key when the config is invalid.
  explicit VpackExtractor(const VpackConfig& config = {}, WorkerPool* pool = nullptr);
  ~VpackExtractor();
  VpackExtractor(VpackExtractor&&) noexcept;

  /// image: CV_8UC3 (BGR), CV_8UC4 (BGRA) or CV_8UC1 (grey, histograms then fall in grey bins).
  /// Throws std::invalid_argument with a clear message for empty, too small or unsupported images.
  /// Thread-safe. Working images and the keypoint detector are kept between calls, so a stream of
  /// frames of one size reuses them; a call made while another is running works in memory of its own.
  Fingerprint extract(const cv::Mat& image, VpackDiagnostics* diagnostics = nullptr) const;
  /// The same, with the frame's grey given (`luma`: CV_8UC1, the image's size; a YUYV camera's Y
  /// plane) for edges and keypoints instead of converting `image`, which then only feeds the colour
  /// histograms. An empty `luma` means: convert, as above.
  Fingerprint extract(const cv::Mat& image, const cv::Mat& luma,
                      VpackDiagnostics* diagnostics = nullptr) const;

  const VpackConfig& config() const { return config_; }

 private:
  VpackConfig config_;
  WorkerPool* pool_;
  VerticalEdgeDetector edge_detector_;
  HclHistogram histogram_;
  KeypointExtractor keypoints_;
  struct Scratch;
  std::unique_ptr<Scratch> scratch_;  ///< never null (moved-from extractors aside)
};

/// Draws edges (red lines), subregion borders and keypoints on a copy of the image (Figure 3.11).
cv::Mat drawFingerprint(const cv::Mat& image, const Fingerprint& fingerprint);

}  // namespace toposlam
