// Routes through a simulated world and the camera trajectory they produce. A route is a waypoint path;
// the robot turns in place towards the next waypoint (at `turn_rate`), drives straight to it at
// `speed` x the waypoint's speed factor, and pauses there if asked. The trajectory is sampled at a
// fixed frame rate. Plain values, no state: thread-safe.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "toposlam/sim/world.hpp"

namespace toposlam::sim {

struct Pose {
  double x = 0, y = 0;   ///< metres
  double heading = 0;    ///< radians, counter-clockwise from +x, wrapped to (-pi, pi]
};

struct RouteConfig {
  double speed = 0.5;             ///< m/s on a leg with speed factor 1
  double turn_rate = 1.0;         ///< rad/s when turning in place
  std::string validate() const;
};

/// One keyframe of the continuous trajectory (heading unwrapped so it interpolates linearly).
struct TrajectoryKey {
  double time_s = 0;
  double x = 0, y = 0, heading = 0;
  int traversal = 0;  ///< which traversal of the loop this part belongs to (0 = first)
};

class Trajectory {
 public:
  Trajectory() = default;
  explicit Trajectory(std::vector<TrajectoryKey> keys);
  double duration() const;  ///< seconds
  Pose poseAt(double time_s) const;
  int traversalAt(double time_s) const;
  const std::vector<TrajectoryKey>& keys() const { return keys_; }

 private:
  std::vector<TrajectoryKey> keys_;
};

/// Route names understood for every world:
///   loop      one traversal of the world's loop;   loopN (N = 1..20) N traversals in the same direction
///   reverse   the loop in the opposite direction;  both   the loop forwards, then backwards
///   stopgo    two traversals with seeded pauses (1.5..4 s) and speed changes (x0.4..x1.6)
///   stops     two traversals, the first with three 10 s stops and one leg at a third of the speed
///   plus the world's own named routes.
std::vector<std::string> routeNames(const World& world);
/// Throws std::invalid_argument naming the route and listing the allowed ones if unknown.
Trajectory buildTrajectory(const World& world, const std::string& route, const RouteConfig& config,
                           std::uint64_t seed);

}  // namespace toposlam::sim
