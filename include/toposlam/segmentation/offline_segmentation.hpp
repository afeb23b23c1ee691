// The rows of an offline run's segmentation (frames.csv, places.csv, dropped_places.csv, lambda2.svg; see
// docs/run-folder.md) and their writers, which take streams (no files here). OfflineMapper
// (src/pipeline) fills the rows as it drives the stages: frames numbered 0, 1, 2, ... in stream order,
// whatever the source's own sequence numbers.
#pragma once

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "toposlam/core/svg_plot.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"

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
