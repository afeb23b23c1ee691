// The simulated indoor world (issue 3): a floor plan of rooms (polygons) joined by doors, plus the things
// that make a room look like a room to VPACK: door frames, shelves and desks (structural vertical edges),
// posters and boards (keypoints), per-room wall and floor colours.
//
// Units: metres and radians; x east, y north, heading counter-clockwise from +x. A World is a plain
// value (copyable, no hidden state); FloorPlan/decorate() build one, Scene (renderer.hpp) compiles it for
// drawing. Thread-safety: const member functions may be called from any thread.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace toposlam::sim {

using Point = cv::Point2d;

/// One waypoint of a route; the robot turns in place towards the next one, then drives straight.
struct Waypoint {
  Point position;
  double pause_s = 0.0;       ///< stand still this long on arrival (seconds)
  double speed_factor = 1.0;  ///< multiplies the route speed on the leg that ends here
};

enum class FloorPattern : std::uint8_t { Carpet, Tiles, Wood };

struct Room {
  int id = 0;                    ///< index in World::rooms, the ground-truth place label
  std::string name;
  std::vector<Point> polygon;    ///< counter-clockwise, no self-intersection
  cv::Vec3b wall_bgr{230, 230, 230};
  cv::Vec3b floor_bgr{120, 120, 120};
  FloorPattern floor_pattern = FloorPattern::Carpet;
  int posters = 2;   ///< how many posters decorate() hangs (seeded placement and content)
  int boards = 0;    ///< whiteboards
  int shelves = 1;   ///< bookshelves against the walls
  int desks = 0;
  /// Decorate this room from its own seed instead of the world's (rooms of one shape, doors and seed are
  /// look-alikes: the ambiguity the topology filter must carry until later places settle it).
  std::optional<std::uint64_t> decoration_seed;
};

struct Door {
  Point centre;        ///< on the wall shared by the two rooms
  double width = 0.9;  ///< metres
  int room_a = -1;     ///< filled by World::resolveDoors()
  int room_b = -1;
  Point along{1, 0};   ///< unit vector along the wall (filled by resolveDoors)
};

/// Sign: small notices, switches and pictograms that decorate() adds along every wall (about one per
/// 1.5 m of free wall), so that no wall is bare of keypoints.
enum class DecorKind : std::uint8_t { Poster, Board, Sign };

/// A flat textured rectangle on a room wall. `edge` is the polygon edge (vertex edge -> edge + 1),
/// u is the distance along that edge from its first vertex, v the height above the floor (metres).
struct WallDecor {
  int room = 0;
  int edge = 0;
  double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
  DecorKind kind = DecorKind::Poster;
  std::uint64_t texture_seed = 0;  ///< the same seed draws the same picture on every visit
};

enum class FurnitureKind : std::uint8_t { Shelf, Desk };

/// An axis-aligned box standing on the floor, its front facing `front` (unit vector into the room).
struct Furniture {
  int room = 0;
  FurnitureKind kind = FurnitureKind::Shelf;
  Point centre;
  double width = 1.0, depth = 0.4, height = 1.9;  ///< metres; width along the wall
  Point front{0, 1};
  cv::Vec3b body_bgr{60, 90, 130};
  std::uint64_t texture_seed = 0;
};

struct World {
  std::string name;
  double wall_height = 2.5;  ///< metres
  double door_height = 2.05; ///< metres
  cv::Vec3b frame_bgr{40, 55, 75};  ///< door frame colour
  cv::Vec3b ceiling_bgr{235, 238, 240};
  std::vector<Room> rooms;
  std::vector<Door> doors;
  std::vector<WallDecor> decor;
  std::vector<Furniture> furniture;
  std::vector<Waypoint> loop;  ///< a closed tour through the rooms (returns to loop[0])
  std::vector<std::pair<std::string, std::vector<Waypoint>>> named_routes;

  /// Room whose polygon contains p (boundary counts as inside of the first such room), or -1.
  int roomContaining(const Point& p) const;
  /// Ground-truth place label: -1 within `doorway_depth` metres of a door opening, else roomContaining().
  int placeLabel(const Point& p, double doorway_depth = 0.25) const;
  /// Finds the two rooms of every door and its direction; throws std::invalid_argument naming the door
  /// when a door does not lie on a wall shared by exactly two rooms.
  void resolveDoors();
  /// Bounding box of all rooms (metres).
  cv::Rect2d bounds() const;
  /// "" when valid, else a description of the first problem (room polygons, doors, loop inside rooms).
  std::string validate() const;
};

/// Point-in-polygon (even-odd rule); points on the boundary count as inside.
bool polygonContains(const std::vector<Point>& polygon, const Point& p);
/// Signed area (positive when counter-clockwise).
double signedArea(const std::vector<Point>& polygon);
/// Distance from p to the segment [a, b].
double distanceToSegment(const Point& p, const Point& a, const Point& b);

}  // namespace toposlam::sim
