// VPACK extraction (thesis Algorithm 3.2). Two parallel phases on the worker pool:
//   A. keypoint candidates over the whole frame (one task) alongside the subregion histograms;
//   B. per-subregion keypoint selection.
// Each task writes only its own slot, so the result does not depend on the number of workers.
#include "toposlam/fingerprint/vpack_extractor.hpp"

#include <cstring>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "toposlam/core/worker_pool.hpp"

namespace toposlam {

std::string VpackConfig::validate() const {
  if (std::string p = edges.validate(); !p.empty()) return p;
  if (std::string p = histogram.validate(); !p.empty()) return p;
  if (std::string p = keypoints.validate(); !p.empty()) return p;
  std::ostringstream e;
  if (min_image_width < 4 || min_image_height < 4)
    e << "fingerprint.min_image_width/min_image_height: must be >= 4, got " << min_image_width << "x"
      << min_image_height;
  return e.str();
}

namespace {
const VpackConfig& validated(const VpackConfig& config) {
  if (std::string problem = config.validate(); !problem.empty()) throw std::invalid_argument(problem);
  return config;
}
}  // namespace

/// What one extraction works in, kept between frames: frames of one size reuse the same memory and
/// the detector is made once. One extraction at a time uses it; a concurrent one makes its own.
struct VpackExtractor::Scratch {
  std::mutex busy;
  cv::Mat grey;  ///< the frame's grey when it has to be converted
  cv::Mat bgr;   ///< a BGRA frame without its alpha
  cv::Ptr<cv::Feature2D> detector;
  VerticalEdgeScratch edge_scratch;
  VerticalEdges edges;
  KeypointCandidates candidates;
  std::vector<std::vector<int>> selected;  ///< per subregion, indices into candidates
};

VpackExtractor::VpackExtractor(const VpackConfig& config, WorkerPool* pool)
    : config_(validated(config)),
      pool_(pool),
      edge_detector_(config.edges),
      histogram_(config.histogram),
      keypoints_(config.keypoints),
      scratch_(std::make_unique<Scratch>()) {}

VpackExtractor::~VpackExtractor() = default;
VpackExtractor::VpackExtractor(VpackExtractor&&) noexcept = default;

Fingerprint VpackExtractor::extract(const cv::Mat& image, VpackDiagnostics* diagnostics) const {
  return extract(image, cv::Mat(), diagnostics);
}

Fingerprint VpackExtractor::extract(const cv::Mat& image, const cv::Mat& luma,
                                    VpackDiagnostics* diagnostics) const {
  if (image.empty()) throw std::invalid_argument("cannot fingerprint an empty image");
  if (image.depth() != CV_8U)
    throw std::invalid_argument("cannot fingerprint an image with " + std::to_string(image.elemSize1() * 8) +
                                "-bit channels (expected 8-bit grey, BGR or BGRA)");
  if (image.cols < config_.min_image_width || image.rows < config_.min_image_height) {
    std::ostringstream e;
    e << "image is " << image.cols << "x" << image.rows << " pixels; VPACK needs at least "
      << config_.min_image_width << "x" << config_.min_image_height;
    throw std::invalid_argument(e.str());
  }
  if (!luma.empty() && (luma.type() != CV_8UC1 || luma.size() != image.size()))
    throw std::invalid_argument(
        "the grey plane given with a frame must be 8-bit, one channel, of the frame's size");

  // The shared scratch when free; a concurrent extraction works in its own.
  std::unique_lock<std::mutex> lock(scratch_->busy, std::try_to_lock);
  std::unique_ptr<Scratch> own;
  Scratch* scratch = scratch_.get();
  if (!lock.owns_lock()) {
    own = std::make_unique<Scratch>();
    scratch = own.get();
  }

  // Colour only feeds the histograms; edges and keypoints want grey, taken as it came when it did.
  cv::Mat colour, grey;
  switch (image.channels()) {
    case 1:
      grey = image;
      colour = image;  // histograms in the grey bins, straight from the grey pixels
      break;
    case 3:
      colour = image;
      if (luma.empty()) cv::cvtColor(image, scratch->grey, cv::COLOR_BGR2GRAY);
      grey = luma.empty() ? scratch->grey : luma;
      break;
    case 4:
      cv::cvtColor(image, scratch->bgr, cv::COLOR_BGRA2BGR);
      colour = scratch->bgr;
      if (luma.empty()) cv::cvtColor(image, scratch->grey, cv::COLOR_BGRA2GRAY);
      grey = luma.empty() ? scratch->grey : luma;
      break;
    default:
      throw std::invalid_argument("cannot fingerprint an image with " + std::to_string(image.channels()) +
                                  " channels (expected 1, 3 or 4)");
  }

  Fingerprint fingerprint;
  fingerprint.image_width = image.cols;
  fingerprint.image_height = image.rows;
  fingerprint.backend = keypoints_.backend();

  VerticalEdges& edges = scratch->edges;
  edge_detector_.detect(grey, edges, scratch->edge_scratch);
  // An edge on the first or last column would leave an empty subregion.
  for (int column : edges.columns)
    if (column > 0 && column < image.cols) fingerprint.edge_columns.push_back(column);
  fingerprint.subregions.reserve(fingerprint.edge_columns.size() + 1);
  int begin = 0;
  for (int column : fingerprint.edge_columns) {
    fingerprint.subregions.push_back({begin, column, {}, 0, 0});
    begin = column;
  }
  fingerprint.subregions.push_back({begin, image.cols, {}, 0, 0});
  const std::size_t regions = fingerprint.subregions.size();

  // Phase A: task 0 detects keypoint candidates, tasks 1..n compute the histograms.
  KeypointCandidates& candidates = scratch->candidates;
  if (config_.keypoints.max_keypoints > 0 && scratch->detector.empty())
    scratch->detector = keypoints_.createDetector();
  const bool grey_colour = colour.channels() == 1;
  auto phase_a = [&](std::size_t task) {
    if (task == 0) {
      if (scratch->detector.empty()) {
        candidates.keypoints.clear();
        candidates.descriptors.release();
      } else {
        keypoints_.detect(*scratch->detector, grey, candidates);
      }
    } else {
      Subregion& s = fingerprint.subregions[task - 1];
      s.histogram = grey_colour ? histogram_.computeGrey(colour, s.column_begin, s.column_end)
                                : histogram_.compute(colour, s.column_begin, s.column_end);
    }
  };
  // Phase B: each subregion keeps its share of the candidates.
  const std::vector<int> budgets = keypoints_.budgets(fingerprint.subregions, image.cols);
  std::vector<std::vector<int>>& selected = scratch->selected;
  if (selected.size() < regions) selected.resize(regions);
  auto phase_b = [&](std::size_t i) {
    const Subregion& s = fingerprint.subregions[i];
    selected[i] = keypoints_.select(candidates, s.column_begin, s.column_end, budgets[i]);
  };
  if (pool_ != nullptr) {
    pool_->run(regions + 1, phase_a);
    pool_->run(regions, phase_b);
  } else {
    for (std::size_t t = 0; t < regions + 1; ++t) phase_a(t);
    for (std::size_t t = 0; t < regions; ++t) phase_b(t);
  }

  // The kept candidates, copied once, straight into the fingerprint's own rows.
  std::size_t total = 0;
  for (std::size_t i = 0; i < regions; ++i) total += selected[i].size();
  fingerprint.keypoints.reserve(total);
  if (total > 0)
    fingerprint.descriptors.create(static_cast<int>(total), candidates.descriptors.cols,
                                   candidates.descriptors.type());
  const std::size_t row_bytes =
      total > 0 ? fingerprint.descriptors.cols * fingerprint.descriptors.elemSize() : 0;
  int row = 0;
  for (std::size_t i = 0; i < regions; ++i) {
    Subregion& s = fingerprint.subregions[i];
    s.keypoint_begin = row;
    for (int index : selected[i]) {
      cv::KeyPoint k = candidates.keypoints[static_cast<std::size_t>(index)];
      k.class_id = static_cast<int>(i);
      fingerprint.keypoints.push_back(k);
      std::memcpy(fingerprint.descriptors.ptr(row), candidates.descriptors.ptr(index), row_bytes);
      ++row;
    }
    s.keypoint_end = row;
  }
  if (diagnostics != nullptr) diagnostics->edges = edges;
  return fingerprint;
}

cv::Mat drawFingerprint(const cv::Mat& image, const Fingerprint& fingerprint) {
  cv::Mat canvas;
  if (image.channels() == 1)
    cv::cvtColor(image, canvas, cv::COLOR_GRAY2BGR);
  else if (image.channels() == 4)
    cv::cvtColor(image, canvas, cv::COLOR_BGRA2BGR);
  else
    canvas = image.clone();
  for (int column : fingerprint.edge_columns)
    cv::line(canvas, {column, 0}, {column, canvas.rows - 1}, cv::Scalar(0, 0, 255), 2);
  for (const cv::KeyPoint& k : fingerprint.keypoints)
    cv::circle(canvas, k.pt, std::max(3, static_cast<int>(k.size / 4)), cv::Scalar(0, 255, 0), 1, cv::LINE_AA);
  // A strip of each subregion's dominant histogram colour under the frame.
  const int strip = std::max(8, canvas.rows / 24);
  cv::Mat out(canvas.rows + strip, canvas.cols, CV_8UC3, cv::Scalar(0, 0, 0));
  canvas.copyTo(out(cv::Rect(0, 0, canvas.cols, canvas.rows)));
  for (const Subregion& s : fingerprint.subregions) {
    int best = 0;
    for (int b = 1; b < kHistogramBins; ++b)
      if (s.histogram[b] > s.histogram[best]) best = b;
    cv::Scalar colour;
    if (best < kHueBins) {
      cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(best * 180 / kHueBins, 255, 255)), rgb;
      cv::cvtColor(hsv, rgb, cv::COLOR_HSV2BGR);
      const auto px = rgb.at<cv::Vec3b>(0, 0);
      colour = cv::Scalar(px[0], px[1], px[2]);
    } else {
      const double level = 255.0 * (kHistogramBins - 1 - best) / (kGreyBins - 1);
      colour = cv::Scalar(level, level, level);
    }
    cv::rectangle(out, cv::Rect(s.column_begin, canvas.rows, s.width(), strip), colour, cv::FILLED);
  }
  return out;
}

}  // namespace toposlam
