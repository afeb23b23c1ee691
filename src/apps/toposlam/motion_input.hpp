// The robot's motion for the offline commands: a CSV of wheel-odometry samples in the frames' time base
// (`time_s,distance_m,speed_mps[,turn_rate_rps]`: time of the sample, distance driven since the previous
// one, speed, and optionally the yaw rate), as
// `toposlam sim` writes it (motion.csv) or a robot's log gives it. `map --motion FILE` feeds it to the
// segmenter's MotionGate, the same gate toposlamd feeds from TOPOSLAM_MOTION (docs/segmentation.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "toposlam/pipeline/algorithm_stages.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"
#include "toposlam/segmentation/motion_gate.hpp"

namespace toposlam::cli {

struct MotionCsvSample {
  double time_s = 0.0;
  double distance_m = 0.0;
  double speed_mps = 0.0;
  double turn_rate_rps = 0.0;
};

/// Reads a motion CSV (header `time_s,distance_m,speed_mps` or `time_s,distance_m,speed_mps,turn_rate_rps`). Throws std::runtime_error naming the file
/// and line for a missing file, a wrong header, a short or non-numeric row, or a time that goes back.
std::vector<MotionCsvSample> readMotionCsv(const std::string& path);

/// Feeds the segmentation stage's MotionGate (the one toposlamd feeds from TOPOSLAM_MOTION) the samples in
/// time order up to each frame's time: feedUpTo(t, stage) gives it every sample at or before t not given
/// yet.
class MotionReplay {
 public:
  explicit MotionReplay(std::vector<MotionCsvSample> samples) : samples_(std::move(samples)) {}
  void feedUpTo(double frame_time_s, FiedlerSegmentationStage& stage);

 private:
  std::vector<MotionCsvSample> samples_;
  std::size_t next_ = 0;
};

/// `--motion FILE` and `--window-m M`, shared by `map` and `segment`.
struct MotionOptions {
  std::string file;     ///< motion CSV; empty: segment by time
  double window_m = 0;  ///< with a file: window in metres of travel (0: by time)
};
void addMotionOptions(CLI::App& command, MotionOptions& options);
/// Applies window_m to `config` (validated) and reads the file; std::nullopt without --motion. Throws
/// std::invalid_argument "<command>: ..." for --window-m without --motion or with several sources.
std::optional<MotionReplay> openMotion(const MotionOptions& options, std::size_t sources, const std::string& command,
                                       FiedlerSegmenterConfig& config);
/// "<command>: motion from FILE: N samples, M frames taken standing (not segmented)[, K samples refused]",
/// from the segmentation stage's counts.
std::string motionSummary(const FiedlerSegmentationStage& stage, const MotionOptions& options, const std::string& command);

}  // namespace toposlam::cli
