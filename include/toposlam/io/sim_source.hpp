// The simulated world as a FrameSource (`sim:WORLD?route=R&fps=F&size=WxH&seed=S&...`). Timestamps are
// simulated seconds; the ground truth of the last frame is available for end-to-end tests.
// Query keys: route, fps, size, seed, speed (m/s), fov (degrees), light (day|night|warm|cool),
// noise (grey levels), people (count), pitch (degrees), moved (0|1), and the common rate.
// Not thread-safe: one consumer calls next(); interrupt() (ends the stream early) from any thread.
#pragma once

#include <atomic>
#include <memory>
#include <optional>
#include <string>

#include "toposlam/io/source_uri.hpp"
#include "toposlam/pipeline/frame_source.hpp"
#include "toposlam/sim/simulator.hpp"

namespace toposlam {

/// Reads the sim: query keys into a config; throws FrameSourceError naming the bad key.
sim::SimConfig simConfigFromUri(const SourceUri& uri);

class SimFrameSource : public FrameSource {
 public:
  /// Throws FrameSourceError naming the bad key (config, world file, route).
  explicit SimFrameSource(const sim::SimConfig& config);
  std::string describe() const override;
  std::optional<Frame> next() override;
  void interrupt() override { interrupted_.store(true); }
  std::int64_t frameCountHint() const override { return simulator_->frameCount(); }
  FrameSourceState state() const override { return FrameSourceState::of(SourceKind::Simulator); }
  const sim::Simulator& simulator() const { return *simulator_; }
  /// Ground truth of the frame last returned by next() (default values before the first).
  const sim::GroundTruth& lastTruth() const { return last_truth_; }

 private:
  std::unique_ptr<sim::Simulator> simulator_;
  sim::GroundTruth last_truth_;
  std::atomic<bool> interrupted_{false};
};

}  // namespace toposlam
