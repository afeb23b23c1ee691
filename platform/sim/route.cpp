// Routes -> trajectories: turn in place, drive straight, pause; several traversals, reversal, and the
// seeded stop-and-go variant (the thesis' failure case for segmentation: pauses and speed changes).
#include "toposlam/sim/route.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>

namespace toposlam::sim {

namespace {

double wrapAngle(double angle) {
  angle = std::fmod(angle + std::numbers::pi, 2 * std::numbers::pi);
  if (angle <= 0) angle += 2 * std::numbers::pi;
  return angle - std::numbers::pi;
}

struct Leg {
  std::vector<Waypoint> path;  // waypoints visited in order (the first is the start of this traversal)
  int traversal = 0;
};

/// Parses "loopN"; returns 0 when `route` is not of that form.
int loopCount(const std::string& route) {
  if (route == "loop") return 1;
  if (!route.starts_with("loop") || route.size() > 6) return 0;
  const std::string digits = route.substr(4);
  if (digits.empty() || !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return 0;
  }
  const int count = std::stoi(digits);
  return count >= 1 && count <= 20 ? count : 0;
}

std::vector<Waypoint> closedLoop(const World& world, bool reversed) {
  std::vector<Waypoint> path = world.loop;
  if (reversed) std::reverse(path.begin(), path.end());
  path.push_back(path.front());  // return to the start
  return path;
}

}  // namespace

std::string RouteConfig::validate() const {
  if (!(speed > 0.01 && speed <= 5)) return "speed: must be in (0.01, 5] m/s";
  if (!(turn_rate > 0.05 && turn_rate <= 10)) return "turn_rate: must be in (0.05, 10] rad/s";
  return "";
}

Trajectory::Trajectory(std::vector<TrajectoryKey> keys) : keys_(std::move(keys)) {
  if (keys_.empty()) throw std::invalid_argument("route: a trajectory needs at least one pose");
}

double Trajectory::duration() const { return keys_.empty() ? 0.0 : keys_.back().time_s; }

Pose Trajectory::poseAt(double time_s) const {
  if (keys_.empty()) return {};
  if (time_s <= keys_.front().time_s) return {keys_.front().x, keys_.front().y, wrapAngle(keys_.front().heading)};
  if (time_s >= keys_.back().time_s) return {keys_.back().x, keys_.back().y, wrapAngle(keys_.back().heading)};
  const auto after = std::upper_bound(keys_.begin(), keys_.end(), time_s,
                                      [](double t, const TrajectoryKey& key) { return t < key.time_s; });
  const TrajectoryKey& b = *after;
  const TrajectoryKey& a = *(after - 1);
  const double span = b.time_s - a.time_s;
  const double f = span > 0 ? (time_s - a.time_s) / span : 1.0;
  return {a.x + f * (b.x - a.x), a.y + f * (b.y - a.y), wrapAngle(a.heading + f * (b.heading - a.heading))};
}

int Trajectory::traversalAt(double time_s) const {
  if (keys_.empty()) return 0;
  const auto after = std::upper_bound(keys_.begin(), keys_.end(), time_s,
                                      [](double t, const TrajectoryKey& key) { return t < key.time_s; });
  if (after == keys_.begin()) return keys_.front().traversal;
  return (after - 1)->traversal;
}

std::vector<std::string> routeNames(const World& world) {
  std::vector<std::string> names;
  if (world.loop.size() >= 2)
    names = {"loop", "loop2", "loop3", "loopN (N = 1..20)", "reverse", "both", "stopgo", "stops"};
  for (const auto& [name, path] : world.named_routes) names.push_back(name);
  return names;
}

Trajectory buildTrajectory(const World& world, const std::string& route, const RouteConfig& config,
                           std::uint64_t seed) {
  if (const std::string problem = config.validate(); !problem.empty()) throw std::invalid_argument(problem);
  std::vector<Leg> traversals;
  const bool has_loop = world.loop.size() >= 2;
  if (const int count = loopCount(route); count > 0 && has_loop) {
    for (int i = 0; i < count; ++i) traversals.push_back({closedLoop(world, false), i});
  } else if (route == "reverse" && has_loop) {
    traversals.push_back({closedLoop(world, true), 0});
  } else if (route == "both" && has_loop) {
    traversals.push_back({closedLoop(world, false), 0});
    traversals.push_back({closedLoop(world, true), 1});
  } else if (route == "stopgo" && has_loop) {
    std::mt19937_64 rng(seed ^ 0x5709609ULL);
    for (int i = 0; i < 2; ++i) {
      Leg leg{closedLoop(world, false), i};
      for (std::size_t w = 1; w < leg.path.size(); ++w) {
        leg.path[w].speed_factor *= std::uniform_real_distribution<double>(0.4, 1.6)(rng);
        if (std::uniform_real_distribution<double>(0, 1)(rng) < 0.35) {
          leg.path[w].pause_s += std::uniform_real_distribution<double>(1.5, 4.0)(rng);
        }
      }
      traversals.push_back(leg);
    }
  } else if (route == "stops" && has_loop) {
    // Issue 17's route: two traversals, the first with three 10 s stops (at the waypoints a fifth, two
    // fifths and three fifths along the loop) and the leg that ends four fifths along at a third of the
    // speed; the second at constant speed.
    Leg first{closedLoop(world, false), 0};
    const std::size_t n = first.path.size() - 1;  // waypoints after the start
    for (const std::size_t k : {1u, 2u, 3u}) first.path[std::max<std::size_t>(1, k * n / 5)].pause_s += 10.0;
    first.path[std::max<std::size_t>(1, 4 * n / 5)].speed_factor /= 3.0;
    traversals.push_back(first);
    traversals.push_back({closedLoop(world, false), 1});
  } else {
    for (const auto& [name, path] : world.named_routes) {
      if (name == route) traversals.push_back({path, 0});
    }
  }
  if (traversals.empty()) {
    std::ostringstream message;
    message << "route: unknown route '" << route << "' for world '" << world.name << "'; allowed:";
    for (const std::string& name : routeNames(world)) message << " " << name;
    throw std::invalid_argument(message.str());
  }

  std::vector<TrajectoryKey> keys;
  const Point start = traversals.front().path[0].position;
  const Point first_target = traversals.front().path[1].position;
  double heading = std::atan2(first_target.y - start.y, first_target.x - start.x);
  double time = 0;
  keys.push_back({time, start.x, start.y, heading, 0});
  for (const Leg& leg : traversals) {
    for (std::size_t w = 1; w < leg.path.size(); ++w) {
      const TrajectoryKey& last = keys.back();
      const Point target = leg.path[w].position;
      const double dx = target.x - last.x, dy = target.y - last.y;
      const double length = std::hypot(dx, dy);
      if (length < 1e-6) continue;
      const double turn = wrapAngle(std::atan2(dy, dx) - heading);
      if (std::abs(turn) > 1e-6) {
        time += std::abs(turn) / config.turn_rate;
        heading += turn;
        keys.push_back({time, last.x, last.y, heading, leg.traversal});
      }
      time += length / (config.speed * leg.path[w].speed_factor);
      keys.push_back({time, target.x, target.y, heading, leg.traversal});
      if (leg.path[w].pause_s > 0) {
        time += leg.path[w].pause_s;
        keys.push_back({time, target.x, target.y, heading, leg.traversal});
      }
    }
  }
  return Trajectory(std::move(keys));
}

}  // namespace toposlam::sim
