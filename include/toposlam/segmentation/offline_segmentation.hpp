// The per-frame pipeline of the offline commands (`toposlam segment`, `toposlam map`): fingerprint a
// frame (VPACK), feed it to the FiedlerSegmenter, and keep the rows of the run folder (frames.csv,
// places.csv, dropped_places.csv, lambda2.svg; see docs/run-folder.md). The two steps are separate
// calls so the caller can time each one; no clocks or files here, writers take streams.
//
// Frames are numbered 0, 1, 2, ... in the order they are given (stream order), whatever the source's
// own sequence numbers. Not thread-safe; one instance per stream.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "toposlam/core/svg_plot.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"
#include "toposlam/segmentation/motion_gate.hpp"

namespace toposlam {

/// One row of frames.csv.
struct SegmentationFrameRecord {
  std::int64_t frame = 0;
  double time_s = 0.0;
  std::string name;
  std::optional<double> lambda2;
  std::int64_t place = -1;  ///< kept place index, -1 while open or when dropped
  bool in_dropped_place = false;
  int keypoints = 0;  ///< keypoints of this frame's fingerprint
};

struct SegmentationRun {
  std::vector<SegmentationFrameRecord> frames;
  std::vector<SegmentedPlace> places;          ///< kept, in closing order (index 0, 1, ...)
  std::vector<SegmentedPlace> dropped_places;  ///< dropped, in closing order
};

class OfflineSegmentation {
 public:
  /// `extractor` and `similarity` must outlive this object. Throws std::invalid_argument on a bad config.
  OfflineSegmentation(const VpackExtractor& extractor, const SimilarityMeasure& similarity,
                      const FiedlerSegmenterConfig& config);

  /// Step 1: the VPACK fingerprint of one frame (BGR, BGRA or grey). Throws std::invalid_argument for
  /// images the extractor refuses.
  std::shared_ptr<const Fingerprint> fingerprint(const cv::Mat& image) const;

  /// Step 2: segments the next frame (numbered in call order from 0) and records its row. Returns the
  /// step (lambda2 and, when a valley closed one, the place). `motion`: the robot's motion at the frame
  /// (MotionGate::at); unknown (the default) segments by time exactly as without motion.
  SegmenterStep segment(double time_s, const std::string& name,
                        std::shared_ptr<const Fingerprint> fingerprint, const MotionState& motion = {});

  /// Both steps at once.
  SegmenterStep process(const cv::Mat& image, double time_s, const std::string& name = "");

  /// End of stream: closes the last place (returned when there was one). Call once.
  std::optional<SegmentedPlace> finish();

  const SegmentationRun& run() const { return run_; }
  const FiedlerSegmenter& segmenter() const { return segmenter_; }

 private:
  void record(const SegmentedPlace& place);

  const VpackExtractor& extractor_;
  FiedlerSegmenter segmenter_;
  SegmentationRun run_;
};

/// Per-frame results of the filter for frames.csv (`map`): each kept place's node probability and each
/// frame's loop-closure detection (docs/run-folder.md).
struct FrameLoopColumns {
  std::vector<double> place_probability;  ///< by kept place
  std::vector<std::int64_t> match_frame;  ///< by frame, -1: no detection
  std::vector<double> match_score;        ///< by frame
};

/// frames.csv: `frame,time,name,lambda2,place,node` (+ `node_probability,match,match_score` with
/// `loop`). `place_nodes[p]` is the node of kept place p (missing or no vector: -1). Names are quoted
/// as CSV fields when they hold a comma, a quote or a line break.
void writeFramesCsv(std::ostream& out, const SegmentationRun& run,
                    const std::vector<std::int64_t>& place_nodes = {}, const FrameLoopColumns* loop = nullptr);
/// places.csv / dropped_places.csv: `place,first,last,representative,keypoints,node`.
void writePlacesCsv(std::ostream& out, const std::vector<SegmentedPlace>& places,
                    const std::vector<std::int64_t>& place_nodes = {});
/// lambda2 over time with the kept places' borders as dashed lines (grey for dropped ones) and the
/// valley detector's gamma as a dotted reference (thesis Figure 4.10). x is the frame number.
SvgPlot lambda2Plot(const SegmentationRun& run, const FiedlerSegmenterConfig& config,
                    const std::string& title);

}  // namespace toposlam
