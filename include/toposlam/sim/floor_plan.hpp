// Floor plans: the built-in worlds (`office`, `home`) and worlds read from a small YAML file, plus the
// seeded procedural decoration (posters, boards, shelves, desks) of their rooms.
//
// YAML format (see docs/simulator.md for a full example):
//   name: lab
//   wall_height: 2.5                      # metres (optional)
//   rooms:
//     - name: corridor
//       rect: [0, 0, 24, 2.2]             # x0, y0, x1, y1 in metres, or polygon: [[x, y], ...]
//       wall: [232, 232, 228]             # RGB 0..255
//       floor: [110, 110, 115]
//       floor_pattern: carpet             # carpet | tiles | wood
//       posters: 3                        # counts of seeded decorations (optional)
//       boards: 1
//       shelves: 1
//       desks: 0
//   doors:
//     - at: [3, 2.2]                      # a point on the wall shared by two rooms
//       width: 0.9
//   loop: [[2, 1.1], [10, 1.1], ...]      # closed tour; a waypoint may be {at: [x, y], pause: 2, speed: 0.5}
//   routes:                                # optional extra named routes (open paths)
//     corridor: [[1, 1.1], [23, 1.1]]
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "toposlam/sim/world.hpp"

namespace toposlam::sim {

/// Names of the built-in worlds ("office", "home").
std::vector<std::string> builtinWorldNames();
/// The YAML text of a built-in world; throws std::invalid_argument listing the names if unknown.
std::string builtinWorldYaml(const std::string& name);

/// Parses a floor plan (rooms, doors, routes) without decoration. Throws std::invalid_argument with the
/// offending key (e.g. "rooms[2].rect: expected 4 numbers") on malformed input. `origin` names the text
/// in messages (file name or world name).
World parseFloorPlan(const std::string& yaml_text, const std::string& origin);
/// Reads a YAML file; throws std::invalid_argument naming the path when it cannot be read.
World loadFloorPlanFile(const std::string& path);
/// A built-in world name, or a path to a .yaml/.yml floor plan.
World loadWorld(const std::string& name_or_path);

/// Hangs posters/boards and places shelves/desks in every room as its counts ask, away from doors and
/// each other. Deterministic in `seed`. Replaces any existing decoration.
void decorate(World& world, std::uint64_t seed);

/// A copy of the furniture moved along its wall by 0.3..1.0 m where there is room (seeded): the
/// "moved furniture between traversals" variation.
std::vector<Furniture> moveFurniture(const World& world, std::uint64_t seed);

}  // namespace toposlam::sim
