// The built-in worlds, written in the same YAML floor-plan format users can load from a file.
//   office: a 24 m corridor, four look-alike offices (white and grey walls; carpets blue, brown, green, plum)
//           and a printer/kitchen room with two doors, like the thesis' KTH office floor.
//   home:   a hall and four colourful rooms (living room, kitchen, bedroom, bathroom).
// Both have a closed `loop` visiting every room; routes (loop2, both, stopgo, ...) are built from it.
#include <stdexcept>
#include <string>
#include <vector>

#include "toposlam/sim/floor_plan.hpp"

namespace toposlam::sim {

namespace {

const char* const kOfficeYaml = R"(
name: office
wall_height: 2.5
rooms:
  - name: corridor
    rect: [0, 0, 24, 2.2]
    wall: [228, 228, 224]
    floor: [104, 106, 110]
    floor_pattern: carpet
    posters: 5
    boards: 0
    shelves: 0
  - name: office 1
    rect: [0, 2.2, 6, 7.2]
    wall: [238, 238, 236]
    floor: [60, 82, 138]
    posters: 2
    boards: 1
    shelves: 2
    desks: 1
  - name: office 2
    rect: [6, 2.2, 12, 7.2]
    wall: [222, 223, 220]
    floor: [138, 100, 62]
    posters: 3
    boards: 0
    shelves: 1
    desks: 2
  - name: office 3
    rect: [12, 2.2, 18, 7.2]
    wall: [240, 237, 228]
    floor: [70, 128, 76]
    posters: 2
    boards: 1
    shelves: 1
    desks: 1
  - name: office 4
    rect: [18, 2.2, 24, 7.2]
    wall: [214, 218, 224]
    floor: [128, 70, 112]
    posters: 3
    boards: 0
    shelves: 2
    desks: 1
  - name: printer room
    rect: [8, -4, 16, 0]
    wall: [232, 230, 222]
    floor: [182, 182, 176]
    floor_pattern: tiles
    posters: 3
    boards: 1
    shelves: 2
    desks: 0
doors:
  - {at: [2, 2.2], width: 0.9}
  - {at: [8, 2.2], width: 0.9}
  - {at: [12, 4.7], width: 0.9}
  - {at: [16, 2.2], width: 0.9}
  - {at: [21, 2.2], width: 0.9}
  - {at: [10, 0], width: 0.9}
  - {at: [14, 0], width: 0.9}
loop:
  - [1, 1.1]
  - [8, 1.1]
  - [8, 3.2]
  - [9, 4.7]
  - [13.5, 4.7]
  - [16, 3.4]
  - [16, 1.1]
  - [21, 1.1]
  - [21, 5.5]
  - [21, 1.1]
  - [14, 1.1]
  - [14, -2]
  - [10, -2]
  - [10, 1.1]
  - [2, 1.1]
  - [2, 4.6]
  - [2, 1.1]
routes:
  corridor: [[1, 1.1], [23, 1.1], [1, 1.1]]
)";

const char* const kHomeYaml = R"(
name: home
wall_height: 2.4
rooms:
  - name: hall
    rect: [0, 0, 10, 2]
    wall: [226, 214, 186]
    floor: [150, 108, 70]
    floor_pattern: wood
    posters: 3
    shelves: 1
  - name: living room
    rect: [0, 2, 6, 7]
    wall: [236, 196, 110]
    floor: [168, 118, 78]
    floor_pattern: wood
    posters: 3
    shelves: 2
    desks: 1
  - name: kitchen
    rect: [6, 2, 10, 7]
    wall: [150, 205, 160]
    floor: [205, 205, 194]
    floor_pattern: tiles
    posters: 2
    shelves: 2
    desks: 1
  - name: bedroom
    rect: [0, -5, 6, 0]
    wall: [140, 168, 222]
    floor: [172, 150, 164]
    floor_pattern: carpet
    posters: 3
    shelves: 1
    desks: 1
  - name: bathroom
    rect: [6, -3.5, 10, 0]
    wall: [238, 168, 182]
    floor: [222, 230, 236]
    floor_pattern: tiles
    posters: 2
    shelves: 1
doors:
  - {at: [2, 2], width: 0.85}
  - {at: [6, 4.5], width: 0.85}
  - {at: [8, 2], width: 0.85}
  - {at: [3, 0], width: 0.85}
  - {at: [8, 0], width: 0.8}
loop:
  - [1, 1]
  - [2, 1]
  - [2, 3.5]
  - [4, 4.5]
  - [7.5, 4.5]
  - [8, 3.2]
  - [8, 1]
  - [8, -1.8]
  - [8, 1]
  - [3, 1]
  - [3, -2.5]
  - [3, 1]
routes:
  hall: [[0.8, 1], [9.2, 1], [0.8, 1]]
)";

}  // namespace

std::vector<std::string> builtinWorldNames() { return {"office", "home"}; }

std::string builtinWorldYaml(const std::string& name) {
  if (name == "office") return kOfficeYaml;
  if (name == "home") return kHomeYaml;
  throw std::invalid_argument("world: unknown built-in world '" + name +
                              "'; allowed: office, home, or a path to a .yaml floor plan");
}

}  // namespace toposlam::sim
