// Floor-plan parsing (YAML) and the seeded procedural decoration of rooms: posters and boards on free
// wall stretches, shelves and desks against walls, all clear of doors and of the routes.
#include "toposlam/sim/floor_plan.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

namespace toposlam::sim {

namespace {

std::string at(const std::string& origin, const std::string& key) { return origin + ": " + key; }

double readNumber(const YAML::Node& node, const std::string& key) {
  try {
    return node.as<double>();
  } catch (const YAML::Exception&) {
    throw std::invalid_argument(key + ": expected a number");
  }
}

Point readPoint(const YAML::Node& node, const std::string& key) {
  if (!node.IsSequence() || node.size() != 2) throw std::invalid_argument(key + ": expected [x, y] in metres");
  return {readNumber(node[0], key), readNumber(node[1], key)};
}

cv::Vec3b readColour(const YAML::Node& node, const std::string& key) {
  if (!node.IsSequence() || node.size() != 3) throw std::invalid_argument(key + ": expected [r, g, b], 0..255");
  cv::Vec3b bgr;
  for (int c = 0; c < 3; ++c) {
    const double value = readNumber(node[static_cast<std::size_t>(c)], key);
    if (value < 0 || value > 255) throw std::invalid_argument(key + ": colour values must be in 0..255");
    bgr[2 - c] = static_cast<unsigned char>(value);
  }
  return bgr;
}

int readCount(const YAML::Node& node, const std::string& key, int max_value) {
  const double value = readNumber(node, key);
  if (value < 0 || value > max_value || value != std::floor(value)) {
    throw std::invalid_argument(key + ": expected a whole number in 0.." + std::to_string(max_value));
  }
  return static_cast<int>(value);
}

std::vector<Waypoint> readWaypoints(const YAML::Node& node, const std::string& key) {
  if (!node.IsSequence() || node.size() < 2) throw std::invalid_argument(key + ": expected at least 2 waypoints");
  std::vector<Waypoint> waypoints;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string item_key = key + "[" + std::to_string(i) + "]";
    Waypoint waypoint;
    if (node[i].IsMap()) {
      waypoint.position = readPoint(node[i]["at"], item_key + ".at");
      if (node[i]["pause"]) waypoint.pause_s = readNumber(node[i]["pause"], item_key + ".pause");
      if (node[i]["speed"]) waypoint.speed_factor = readNumber(node[i]["speed"], item_key + ".speed");
      if (waypoint.pause_s < 0 || waypoint.pause_s > 600) {
        throw std::invalid_argument(item_key + ".pause: must be in 0..600 seconds");
      }
      if (!(waypoint.speed_factor > 0.05 && waypoint.speed_factor <= 10)) {
        throw std::invalid_argument(item_key + ".speed: must be in (0.05, 10] (a factor of the route speed)");
      }
    } else {
      waypoint.position = readPoint(node[i], item_key);
    }
    waypoints.push_back(waypoint);
  }
  return waypoints;
}

FloorPattern readPattern(const YAML::Node& node, const std::string& key) {
  const std::string name = node.as<std::string>();
  if (name == "carpet") return FloorPattern::Carpet;
  if (name == "tiles") return FloorPattern::Tiles;
  if (name == "wood") return FloorPattern::Wood;
  throw std::invalid_argument(key + ": '" + name + "' is not a floor pattern; allowed: carpet, tiles, wood");
}

// ---- decoration helpers ------------------------------------------------------------------------

struct Interval {
  double begin, end;
};

struct EdgeFrame {
  Point a, direction, inward;
  double length;
};

EdgeFrame edgeFrame(const Room& room, int edge) {
  const Point a = room.polygon[static_cast<std::size_t>(edge)];
  const Point b = room.polygon[(static_cast<std::size_t>(edge) + 1) % room.polygon.size()];
  const double length = std::hypot(b.x - a.x, b.y - a.y);
  const Point direction = (b - a) * (1.0 / length);
  return {a, direction, Point(-direction.y, direction.x), length};
}

/// Stretches of an edge taken by door openings (with their frames and a clearance).
std::vector<Interval> doorIntervals(const World& world, const EdgeFrame& frame, double clearance) {
  std::vector<Interval> taken;
  for (const Door& door : world.doors) {
    if (distanceToSegment(door.centre, frame.a, frame.a + frame.direction * frame.length) > 1e-3) continue;
    const double u = (door.centre - frame.a).dot(frame.direction);
    taken.push_back({u - door.width / 2 - clearance, u + door.width / 2 + clearance});
  }
  return taken;
}

bool overlapsAny(const std::vector<Interval>& taken, double begin, double end) {
  return std::any_of(taken.begin(), taken.end(),
                     [&](const Interval& interval) { return begin < interval.end && interval.begin < end; });
}

std::vector<Point> boxCorners(const Point& centre, const Point& front, double width, double depth) {
  const Point side(front.y, -front.x);
  const Point half_w = side * (width / 2);
  const Point half_d = front * (depth / 2);
  return {centre - half_w - half_d, centre + half_w - half_d, centre + half_w + half_d, centre - half_w + half_d};
}

/// True when some route of the world passes within `clearance` metres of the box.
bool blocksRoutes(const World& world, const std::vector<Point>& corners, double clearance) {
  auto near_path = [&](const std::vector<Waypoint>& path, bool closed) {
    const std::size_t legs = closed ? path.size() : path.size() - 1;
    for (std::size_t i = 0; i < legs; ++i) {
      const Point a = path[i].position;
      const Point b = path[(i + 1) % path.size()].position;
      const double length = std::hypot(b.x - a.x, b.y - a.y);
      const int samples = std::max(1, static_cast<int>(length / 0.05));
      for (int s = 0; s <= samples; ++s) {
        const Point p = a + (b - a) * (static_cast<double>(s) / samples);
        if (polygonContains(corners, p)) return true;
        for (std::size_t c = 0; c < corners.size(); ++c) {
          if (distanceToSegment(p, corners[c], corners[(c + 1) % corners.size()]) < clearance) return true;
        }
      }
    }
    return false;
  };
  if (world.loop.size() >= 2 && near_path(world.loop, true)) return true;
  for (const auto& [name, path] : world.named_routes) {
    if (path.size() >= 2 && near_path(path, false)) return true;
  }
  return false;
}

bool insideRoom(const Room& room, const std::vector<Point>& corners) {
  return std::all_of(corners.begin(), corners.end(), [&](const Point& p) { return polygonContains(room.polygon, p); });
}

bool nearDoor(const World& world, const std::vector<Point>& corners, double clearance) {
  for (const Door& door : world.doors) {
    for (std::size_t c = 0; c < corners.size(); ++c) {
      if (distanceToSegment(door.centre, corners[c], corners[(c + 1) % corners.size()]) <
          door.width / 2 + clearance) {
        return true;
      }
    }
  }
  return false;
}

bool overlapsFurniture(const std::vector<Furniture>& furniture, std::size_t skip, const std::vector<Point>& corners) {
  for (std::size_t i = 0; i < furniture.size(); ++i) {
    if (i == skip) continue;
    const Furniture& other = furniture[i];
    const std::vector<Point> other_corners = boxCorners(other.centre, other.front, other.width + 0.1, other.depth + 0.1);
    for (const Point& p : corners) {
      if (polygonContains(other_corners, p)) return true;
    }
    for (const Point& p : other_corners) {
      if (polygonContains(corners, p)) return true;
    }
  }
  return false;
}

double uniform(std::mt19937_64& rng, double low, double high) {
  return std::uniform_real_distribution<double>(low, high)(rng);
}

/// Picks an edge with probability proportional to its length.
int pickEdge(std::mt19937_64& rng, const Room& room) {
  std::vector<double> lengths;
  for (std::size_t e = 0; e < room.polygon.size(); ++e) lengths.push_back(edgeFrame(room, static_cast<int>(e)).length);
  std::discrete_distribution<int> pick(lengths.begin(), lengths.end());
  return pick(rng);
}

}  // namespace

World parseFloorPlan(const std::string& yaml_text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(origin + ": not valid YAML: " + e.what());
  }
  if (!root.IsMap()) throw std::invalid_argument(origin + ": expected a map with rooms, doors and loop");
  World world;
  try {
    world.name = root["name"] ? root["name"].as<std::string>() : origin;
    if (root["wall_height"]) world.wall_height = readNumber(root["wall_height"], "wall_height");
    world.door_height = std::min(2.05, world.wall_height - 0.2);
    const YAML::Node rooms = root["rooms"];
    if (!rooms || !rooms.IsSequence() || rooms.size() == 0) {
      throw std::invalid_argument("rooms: expected a list of at least one room");
    }
    for (std::size_t r = 0; r < rooms.size(); ++r) {
      const std::string key = "rooms[" + std::to_string(r) + "]";
      const YAML::Node node = rooms[r];
      Room room;
      room.id = static_cast<int>(r);
      room.name = node["name"] ? node["name"].as<std::string>() : "room " + std::to_string(r);
      if (node["rect"]) {
        const YAML::Node rect = node["rect"];
        if (!rect.IsSequence() || rect.size() != 4) throw std::invalid_argument(key + ".rect: expected [x0, y0, x1, y1]");
        const double x0 = readNumber(rect[0], key + ".rect"), y0 = readNumber(rect[1], key + ".rect");
        const double x1 = readNumber(rect[2], key + ".rect"), y1 = readNumber(rect[3], key + ".rect");
        if (!(x1 > x0 + 0.5 && y1 > y0 + 0.5)) {
          throw std::invalid_argument(key + ".rect: need x1 > x0 + 0.5 and y1 > y0 + 0.5 (metres)");
        }
        room.polygon = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
      } else if (node["polygon"] && node["polygon"].IsSequence()) {
        for (std::size_t i = 0; i < node["polygon"].size(); ++i) {
          room.polygon.push_back(readPoint(node["polygon"][i], key + ".polygon[" + std::to_string(i) + "]"));
        }
        if (signedArea(room.polygon) < 0) std::reverse(room.polygon.begin(), room.polygon.end());
      } else {
        throw std::invalid_argument(key + ": needs rect: [x0, y0, x1, y1] or polygon: [[x, y], ...]");
      }
      if (node["wall"]) room.wall_bgr = readColour(node["wall"], key + ".wall");
      if (node["floor"]) room.floor_bgr = readColour(node["floor"], key + ".floor");
      if (node["floor_pattern"]) room.floor_pattern = readPattern(node["floor_pattern"], key + ".floor_pattern");
      if (node["posters"]) room.posters = readCount(node["posters"], key + ".posters", 20);
      if (node["boards"]) room.boards = readCount(node["boards"], key + ".boards", 10);
      if (node["shelves"]) room.shelves = readCount(node["shelves"], key + ".shelves", 10);
      if (node["desks"]) room.desks = readCount(node["desks"], key + ".desks", 10);
      if (node["decoration_seed"]) {
        try {
          room.decoration_seed = node["decoration_seed"].as<std::uint64_t>();
        } catch (const YAML::Exception&) {
          throw std::invalid_argument(key + ".decoration_seed: expected a whole number >= 0");
        }
      }
      world.rooms.push_back(room);
    }
    if (const YAML::Node doors = root["doors"]) {
      for (std::size_t d = 0; d < doors.size(); ++d) {
        const std::string key = "doors[" + std::to_string(d) + "]";
        Door door;
        door.centre = readPoint(doors[d]["at"], key + ".at");
        if (doors[d]["width"]) door.width = readNumber(doors[d]["width"], key + ".width");
        if (!(door.width >= 0.5 && door.width <= 3)) throw std::invalid_argument(key + ".width: must be in 0.5..3 metres");
        world.doors.push_back(door);
      }
    }
    if (root["loop"]) world.loop = readWaypoints(root["loop"], "loop");
    if (const YAML::Node routes = root["routes"]) {
      if (!routes.IsMap()) throw std::invalid_argument("routes: expected a map of name: [waypoints]");
      for (const auto& entry : routes) {
        const std::string name = entry.first.as<std::string>();
        world.named_routes.emplace_back(name, readWaypoints(entry.second, "routes." + name));
      }
    }
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(at(origin, e.what()));
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(origin + ": malformed floor plan: " + e.what());
  }
  try {
    world.resolveDoors();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(at(origin, e.what()));
  }
  if (const std::string problem = world.validate(); !problem.empty()) throw std::invalid_argument(at(origin, problem));
  return world;
}

World loadFloorPlanFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("world: cannot read floor plan file '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  return parseFloorPlan(text.str(), path);
}

World loadWorld(const std::string& name_or_path) {
  for (const std::string& name : builtinWorldNames()) {
    if (name == name_or_path) return parseFloorPlan(builtinWorldYaml(name), name);
  }
  const bool looks_like_file = name_or_path.find('/') != std::string::npos ||
                               name_or_path.ends_with(".yaml") || name_or_path.ends_with(".yml");
  if (!looks_like_file) builtinWorldYaml(name_or_path);  // throws the list of built-in names
  return loadFloorPlanFile(name_or_path);
}

void decorate(World& world, std::uint64_t seed) {
  world.decor.clear();
  world.furniture.clear();
  std::mt19937_64 world_rng(seed * 0x9E3779B97F4A7C15ULL + 0x1234567ULL);
  for (const Room& room : world.rooms) {
    // A room with its own decoration_seed is decorated from it alone: two rooms of one shape with one seed
    // (and doors at the same places) look the same, whatever the world seed.
    std::mt19937_64 own_rng(room.decoration_seed ? *room.decoration_seed * 0x9E3779B97F4A7C15ULL + 0x89ABCDEFULL : 0);
    std::mt19937_64& rng = room.decoration_seed ? own_rng : world_rng;
    const int edges = static_cast<int>(room.polygon.size());
    std::vector<std::vector<Interval>> taken(static_cast<std::size_t>(edges));
    for (int e = 0; e < edges; ++e) taken[static_cast<std::size_t>(e)] = doorIntervals(world, edgeFrame(room, e), 0.35);

    // Furniture first (it needs the most room), then boards and posters on what is left.
    auto place_furniture = [&](FurnitureKind kind) {
      for (int attempt = 0; attempt < 60; ++attempt) {
        const int edge = pickEdge(rng, room);
        const EdgeFrame frame = edgeFrame(room, edge);
        Furniture item;
        item.room = room.id;
        item.kind = kind;
        if (kind == FurnitureKind::Shelf) {
          item.width = uniform(rng, 0.8, 1.4);
          item.depth = uniform(rng, 0.35, 0.45);
          item.height = uniform(rng, 1.6, std::min(2.0, world.wall_height - 0.3));
          static const cv::Vec3b kWoods[] = {{60, 90, 130}, {40, 60, 90}, {150, 170, 190}, {210, 210, 205}, {90, 90, 95}};
          item.body_bgr = kWoods[std::uniform_int_distribution<int>(0, 4)(rng)];
        } else {
          item.width = uniform(rng, 1.2, 1.6);
          item.depth = 0.7;
          item.height = 0.75;
          static const cv::Vec3b kDesks[] = {{150, 175, 200}, {200, 200, 200}, {70, 70, 75}, {110, 140, 170}};
          item.body_bgr = kDesks[std::uniform_int_distribution<int>(0, 3)(rng)];
        }
        item.texture_seed = rng();
        if (frame.length < item.width + 0.2) continue;
        const double u = uniform(rng, item.width / 2 + 0.05, frame.length - item.width / 2 - 0.05);
        if (overlapsAny(taken[static_cast<std::size_t>(edge)], u - item.width / 2, u + item.width / 2)) continue;
        item.front = frame.inward;
        item.centre = frame.a + frame.direction * u + frame.inward * (item.depth / 2 + 0.02);
        const std::vector<Point> corners = boxCorners(item.centre, item.front, item.width, item.depth);
        if (!insideRoom(room, corners) || blocksRoutes(world, corners, 0.6) || nearDoor(world, corners, 0.3) ||
            overlapsFurniture(world.furniture, world.furniture.size(), corners)) {
          continue;
        }
        taken[static_cast<std::size_t>(edge)].push_back({u - item.width / 2 - 0.1, u + item.width / 2 + 0.1});
        world.furniture.push_back(item);
        return;
      }
    };
    for (int i = 0; i < room.shelves; ++i) place_furniture(FurnitureKind::Shelf);
    for (int i = 0; i < room.desks; ++i) place_furniture(FurnitureKind::Desk);

    auto hang = [&](DecorKind kind) {
      for (int attempt = 0; attempt < 60; ++attempt) {
        const int edge = pickEdge(rng, room);
        const EdgeFrame frame = edgeFrame(room, edge);
        WallDecor decor;
        decor.room = room.id;
        decor.edge = edge;
        decor.kind = kind;
        double width = 0, height = 0, bottom = 0;
        if (kind == DecorKind::Poster) {
          width = uniform(rng, 0.45, 1.0);
          height = uniform(rng, 0.5, 0.9);
          bottom = uniform(rng, 1.05, 1.4);
        } else if (kind == DecorKind::Sign) {
          width = uniform(rng, 0.15, 0.35);
          height = uniform(rng, 0.12, 0.3);
          bottom = uniform(rng, 0.9, 1.6);
        } else {
          width = uniform(rng, 1.2, 2.0);
          height = uniform(rng, 0.9, 1.1);
          bottom = 0.9;
        }
        height = std::min(height, world.wall_height - 0.15 - bottom);
        decor.texture_seed = rng();
        if (frame.length < width + 0.3 || height < 0.2) continue;
        const double u = uniform(rng, width / 2 + 0.15, frame.length - width / 2 - 0.15);
        if (overlapsAny(taken[static_cast<std::size_t>(edge)], u - width / 2, u + width / 2)) continue;
        decor.u0 = u - width / 2;
        decor.u1 = u + width / 2;
        decor.v0 = bottom;
        decor.v1 = bottom + height;
        const double gap = kind == DecorKind::Sign ? 0.1 : 0.2;
        taken[static_cast<std::size_t>(edge)].push_back({decor.u0 - gap, decor.u1 + gap});
        world.decor.push_back(decor);
        return;
      }
    };
    for (int i = 0; i < room.boards; ++i) hang(DecorKind::Board);
    for (int i = 0; i < room.posters; ++i) hang(DecorKind::Poster);
    double perimeter = 0;
    for (int e = 0; e < edges; ++e) perimeter += edgeFrame(room, e).length;
    const int signs = static_cast<int>(perimeter / 1.5);
    for (int i = 0; i < signs; ++i) hang(DecorKind::Sign);
  }
}

std::vector<Furniture> moveFurniture(const World& world, std::uint64_t seed) {
  std::vector<Furniture> moved = world.furniture;
  std::mt19937_64 rng(seed ^ 0xF00DF00DULL);
  for (std::size_t i = 0; i < moved.size(); ++i) {
    const Room& room = world.rooms[static_cast<std::size_t>(moved[i].room)];
    const Point side(moved[i].front.y, -moved[i].front.x);
    const double shift = uniform(rng, 0.3, 1.0);
    for (const double sign : {1.0, -1.0}) {
      const Point centre = moved[i].centre + side * (sign * shift);
      const std::vector<Point> corners = boxCorners(centre, moved[i].front, moved[i].width, moved[i].depth);
      if (!insideRoom(room, corners) || blocksRoutes(world, corners, 0.6) || nearDoor(world, corners, 0.3) ||
          overlapsFurniture(moved, i, corners)) {
        continue;
      }
      moved[i].centre = centre;
      break;
    }
  }
  return moved;
}

}  // namespace toposlam::sim
