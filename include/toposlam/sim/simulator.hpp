// The simulated camera: a world, a route and the variation switches -> a stream of rendered frames with
// ground truth (room label, pose, traversal). Deterministic: the same config gives the same pixels.
//
// Variation switches (all seeded by `seed`): lighting (day / night / warm / cool), Gaussian sensor noise,
// moving people, a small camera pitch oscillation, and furniture moved between traversals.
// Not thread-safe (one Simulator per thread); rendering is single-threaded.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "toposlam/sim/renderer.hpp"
#include "toposlam/sim/route.hpp"
#include "toposlam/sim/world.hpp"

namespace toposlam::sim {

enum class LightingMode : std::uint8_t { Day, Night, Warm, Cool };
const char* toString(LightingMode mode);
/// "day", "night", "warm", "cool"; throws std::invalid_argument listing them otherwise.
LightingMode parseLightingMode(const std::string& name);

struct SimConfig {
  std::string world = "office";   ///< built-in name or path to a YAML floor plan
  std::string route = "loop";     ///< see routeNames()
  double fps = 5.0;               ///< frames per simulated second
  CameraConfig camera;            ///< size, field of view, height
  RouteConfig motion;             ///< speed, turn rate
  std::uint64_t seed = 1;         ///< decoration and every variation
  LightingMode lighting = LightingMode::Day;
  double noise_sigma = 0.0;       ///< Gaussian sensor noise, grey levels (0..50)
  int people = 0;                 ///< moving occluders (0..20)
  double pitch_deg = 0.0;         ///< amplitude of the camera pitch oscillation (0..10 degrees)
  bool moved_furniture = false;   ///< furniture moves between traversals
  /// "" when valid, else "<key>: <problem, allowed range>".
  std::string validate() const;
};

struct GroundTruth {
  std::int64_t frame = 0;
  double time_s = 0;     ///< simulated seconds
  int room = -1;         ///< place label (World::placeLabel): -1 in a doorway
  Pose pose;
  int traversal = 0;
};

struct SimFrame {
  cv::Mat image;  ///< CV_8UC3 BGR
  GroundTruth truth;
};

class Simulator {
 public:
  /// Throws std::invalid_argument naming the bad key (config, world file, route).
  explicit Simulator(const SimConfig& config);
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  const SimConfig& config() const { return config_; }
  const World& world() const;
  const Trajectory& trajectory() const { return trajectory_; }
  const Renderer& renderer() const { return renderer_; }
  std::int64_t frameCount() const { return frame_count_; }
  /// Ground truth of any frame without rendering it.
  GroundTruth truthOf(std::int64_t frame) const;
  /// Renders frame `frame` (0 <= frame < frameCount()). Random access: the result depends only on the
  /// config and the frame number.
  SimFrame render(std::int64_t frame) const;
  /// Sequential access: the next frame, or nullopt at the end of the route.
  std::optional<SimFrame> next();

 private:
  struct Variation;
  SimConfig config_;
  Renderer renderer_;
  Trajectory trajectory_;
  std::int64_t frame_count_ = 0;
  std::int64_t next_frame_ = 0;
  std::unique_ptr<Variation> variation_;
};

/// Loop-closure ground truth from labels, laid out like samples_GT.bmp: CV_8UC1 N x N, pixel (row i,
/// column j) = 255 when j < i - min_gap and frames i and j carry the same room label >= 0, else 0.
cv::Mat loopClosureMatrix(const std::vector<int>& labels, int min_gap = 0);

}  // namespace toposlam::sim
