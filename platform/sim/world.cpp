// Geometry of the simulated world: point-in-polygon, door resolution, place labels, validation.
#include "toposlam/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace toposlam::sim {

namespace {
constexpr double kOnWallTolerance = 1e-3;  // metres
}

double signedArea(const std::vector<Point>& polygon) {
  double twice_area = 0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Point& a = polygon[i];
    const Point& b = polygon[(i + 1) % polygon.size()];
    twice_area += a.x * b.y - b.x * a.y;
  }
  return twice_area / 2;
}

double distanceToSegment(const Point& p, const Point& a, const Point& b) {
  const Point ab = b - a;
  const double length_sq = ab.dot(ab);
  double t = length_sq > 0 ? (p - a).dot(ab) / length_sq : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  const Point closest = a + t * ab;
  return std::hypot(p.x - closest.x, p.y - closest.y);
}

bool polygonContains(const std::vector<Point>& polygon, const Point& p) {
  const std::size_t n = polygon.size();
  if (n < 3) return false;
  bool inside = false;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Point& a = polygon[i];
    const Point& b = polygon[j];
    if (distanceToSegment(p, a, b) < 1e-9) return true;
    if ((a.y > p.y) != (b.y > p.y)) {
      const double x_cross = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
      if (p.x < x_cross) inside = !inside;
    }
  }
  return inside;
}

int World::roomContaining(const Point& p) const {
  for (const Room& room : rooms) {
    if (polygonContains(room.polygon, p)) return room.id;
  }
  return -1;
}

int World::placeLabel(const Point& p, double doorway_depth) const {
  for (const Door& door : doors) {
    const Point offset = p - door.centre;
    const double along = offset.dot(door.along);
    const double across = offset.x * door.along.y - offset.y * door.along.x;
    if (std::abs(along) <= door.width / 2 && std::abs(across) < doorway_depth) return -1;
  }
  return roomContaining(p);
}

void World::resolveDoors() {
  for (std::size_t d = 0; d < doors.size(); ++d) {
    Door& door = doors[d];
    std::vector<int> found;
    for (const Room& room : rooms) {
      const std::size_t n = room.polygon.size();
      for (std::size_t e = 0; e < n; ++e) {
        const Point& a = room.polygon[e];
        const Point& b = room.polygon[(e + 1) % n];
        if (distanceToSegment(door.centre, a, b) < kOnWallTolerance) {
          found.push_back(room.id);
          const Point ab = b - a;
          door.along = ab * (1.0 / std::hypot(ab.x, ab.y));
          break;
        }
      }
    }
    if (found.size() != 2) {
      std::ostringstream message;
      message << "doors[" << d << "].at: (" << door.centre.x << ", " << door.centre.y << ") lies on the walls of "
              << found.size() << " rooms; a door must lie on a wall shared by exactly 2 rooms";
      throw std::invalid_argument(message.str());
    }
    door.room_a = found[0];
    door.room_b = found[1];
  }
}

cv::Rect2d World::bounds() const {
  double x0 = std::numeric_limits<double>::max(), y0 = x0;
  double x1 = std::numeric_limits<double>::lowest(), y1 = x1;
  for (const Room& room : rooms) {
    for (const Point& p : room.polygon) {
      x0 = std::min(x0, p.x);
      y0 = std::min(y0, p.y);
      x1 = std::max(x1, p.x);
      y1 = std::max(y1, p.y);
    }
  }
  if (rooms.empty()) return {};
  return {x0, y0, x1 - x0, y1 - y0};
}

std::string World::validate() const {
  std::ostringstream message;
  if (rooms.empty()) return "rooms: a world needs at least one room";
  if (!(wall_height > 0.5 && wall_height <= 10)) return "wall_height: must be in (0.5, 10] metres";
  for (std::size_t r = 0; r < rooms.size(); ++r) {
    if (rooms[r].polygon.size() < 3) {
      message << "rooms[" << r << "]: a polygon needs at least 3 corners";
      return message.str();
    }
    if (signedArea(rooms[r].polygon) <= 1e-6) {
      message << "rooms[" << r << "]: polygon must be counter-clockwise with a positive area";
      return message.str();
    }
  }
  for (std::size_t i = 0; i < loop.size(); ++i) {
    if (roomContaining(loop[i].position) < 0) {
      message << "loop[" << i << "]: waypoint (" << loop[i].position.x << ", " << loop[i].position.y
              << ") is outside every room";
      return message.str();
    }
  }
  return "";
}

}  // namespace toposlam::sim
