// The rows of an offline run's segmentation: every frame with its Fiedler value and place, and the kept and
// dropped places. OfflineRunner (src/pipeline) fills them as it drives the stages: frames numbered 0, 1,
// 2, ... in stream order, whatever the source's own sequence numbers. Plain data; the run folder's files
// made from them are run_folder's (toposlam/run_folder/run_folder.hpp).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "toposlam/segmentation/fiedler_segmenter.hpp"

namespace toposlam {

/// One frame of the run.
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

}  // namespace toposlam
