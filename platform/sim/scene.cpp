// Compiles a World into what the ray caster draws: one-sided wall segments (split around door openings,
// with dark door-frame strips and lintels), furniture boxes, decals (posters, boards, baseboards, door
// frames) with their textures, and a 5 cm grid of room ids for the floor colours.
#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "toposlam/sim/floor_plan.hpp"
#include "toposlam/sim/renderer.hpp"
#include "toposlam/sim/textures.hpp"

namespace toposlam::sim {

namespace {

constexpr double kFrameWidth = 0.1;      // door frame strip on each side of an opening (metres)
constexpr double kLintelHeight = 0.1;    // frame above the opening (metres)
constexpr double kBaseboardHeight = 0.08;
const Point kLightDirection(0.6, 0.8);   // unit vector: walls facing it are brightest

double lambert(const Point& a, const Point& b) {
  const Point d = b - a;
  const double length = std::hypot(d.x, d.y);
  const Point normal(-d.y / length, d.x / length);  // the visible side
  return 0.78 + 0.22 * normal.dot(kLightDirection);
}

cv::Vec3b scaled(const cv::Vec3b& colour, double factor) {
  return {cv::saturate_cast<unsigned char>(colour[0] * factor), cv::saturate_cast<unsigned char>(colour[1] * factor),
          cv::saturate_cast<unsigned char>(colour[2] * factor)};
}

}  // namespace

Scene::Scene(const World& world) : world_(world) { compile(world.furniture); }

Scene::Scene(const World& world, const std::vector<Furniture>& furniture) : world_(world) {
  world_.furniture = furniture;
  compile(furniture);
}

void Scene::addSegment(Segment segment, const std::vector<Decal>& decals) {
  segment.decal_begin = static_cast<int>(decals_.size());
  decals_.insert(decals_.end(), decals.begin(), decals.end());
  segment.decal_end = static_cast<int>(decals_.size());
  segment.light = lambert(segment.a, segment.b);
  segments_.push_back(segment);
}

void Scene::compile(const std::vector<Furniture>& furniture) {
  const double wall_top = world_.wall_height;
  const double door_top = world_.door_height;
  // Textures of the wall decor, in decor order.
  std::vector<int> decor_texture(world_.decor.size());
  for (std::size_t i = 0; i < world_.decor.size(); ++i) {
    const WallDecor& decor = world_.decor[i];
    decor_texture[i] = static_cast<int>(textures_.size());
    textures_.push_back(decor.kind == DecorKind::Board
                            ? makeBoardTexture(decor.texture_seed, decor.u1 - decor.u0, decor.v1 - decor.v0)
                            : makePosterTexture(decor.texture_seed, decor.u1 - decor.u0, decor.v1 - decor.v0));
  }

  for (const Room& room : world_.rooms) {
    const std::size_t corners = room.polygon.size();
    const cv::Vec3b baseboard = scaled(room.wall_bgr, 0.55);
    for (std::size_t e = 0; e < corners; ++e) {
      const Point a = room.polygon[e];
      const Point b = room.polygon[(e + 1) % corners];
      const double length = std::hypot(b.x - a.x, b.y - a.y);
      const Point direction = (b - a) * (1.0 / length);
      auto at_u = [&](double u) { return a + direction * u; };
      // Door openings on this edge, as [begin, end) in u.
      std::vector<std::pair<double, double>> openings;
      for (const Door& door : world_.doors) {
        if (distanceToSegment(door.centre, a, b) > 1e-3) continue;
        const double u = (door.centre - a).dot(direction);
        openings.emplace_back(u - door.width / 2, u + door.width / 2);
      }
      std::sort(openings.begin(), openings.end());
      // Decals of this edge: posters and boards hung on it, and the baseboard.
      std::vector<Decal> edge_decals;
      for (std::size_t i = 0; i < world_.decor.size(); ++i) {
        const WallDecor& decor = world_.decor[i];
        if (decor.room != room.id || decor.edge != static_cast<int>(e)) continue;
        edge_decals.push_back({decor.u0, decor.u1, decor.v0, decor.v1, decor_texture[i], {}, false});
      }
      edge_decals.push_back({0.0, length, 0.0, kBaseboardHeight, -1, baseboard, false});

      double u = 0;
      auto add_wall = [&](double u_begin, double u_end, bool frame) {
        if (u_end - u_begin < 1e-6) return;
        Segment segment;
        segment.a = at_u(u_begin);
        segment.b = at_u(u_end);
        segment.bottom = 0;
        segment.top = wall_top;
        segment.bgr = room.wall_bgr;
        segment.u_at_a = u_begin;
        segment.full_height = true;
        std::vector<Decal> decals;
        for (const Decal& decal : edge_decals) {
          if (decal.u0 < u_end && u_begin < decal.u1) decals.push_back(decal);
        }
        if (frame) decals.push_back({u_begin, u_end, 0.0, door_top + kLintelHeight, -1, world_.frame_bgr, false});
        addSegment(segment, decals);
      };
      for (const auto& [open_begin, open_end] : openings) {
        add_wall(u, open_begin - kFrameWidth, false);
        add_wall(open_begin - kFrameWidth, open_begin, true);
        // The lintel over the opening: a partial-height wall with a frame strip at its bottom.
        Segment lintel;
        lintel.a = at_u(open_begin);
        lintel.b = at_u(open_end);
        lintel.bottom = door_top;
        lintel.top = wall_top;
        lintel.bgr = room.wall_bgr;
        lintel.u_at_a = open_begin;
        addSegment(lintel, {{open_begin, open_end, door_top, door_top + kLintelHeight, -1, world_.frame_bgr, false}});
        add_wall(open_end, open_end + kFrameWidth, true);
        u = open_end + kFrameWidth;
      }
      add_wall(u, length, false);
    }
  }

  // Furniture: boxes seen from outside, the front face textured (books, drawers).
  for (const Furniture& item : furniture) {
    const Point side(item.front.y, -item.front.x);
    const Point half_w = side * (item.width / 2);
    const Point half_d = item.front * (item.depth / 2);
    std::vector<Point> box = {item.centre - half_w - half_d, item.centre + half_w - half_d,
                              item.centre + half_w + half_d, item.centre - half_w + half_d};
    if (signedArea(box) > 0) std::reverse(box.begin(), box.end());  // clockwise: edges face outwards
    const int texture = static_cast<int>(textures_.size());
    textures_.push_back(item.kind == FurnitureKind::Shelf
                            ? makeShelfTexture(item.texture_seed, item.width, item.height, item.body_bgr)
                            : makeDeskTexture(item.texture_seed, item.width, item.height, item.body_bgr));
    for (std::size_t i = 0; i < 4; ++i) {
      Segment segment;
      segment.a = box[i];
      segment.b = box[(i + 1) % 4];
      segment.bottom = 0;
      segment.top = item.height;
      segment.bgr = scaled(item.body_bgr, 0.85);
      const Point mid = (segment.a + segment.b) * 0.5;
      const bool is_front = (mid - item.centre).dot(item.front) > item.depth / 4;
      std::vector<Decal> decals;
      if (is_front) {
        const double length = std::hypot(segment.b.x - segment.a.x, segment.b.y - segment.a.y);
        decals.push_back({0.0, length, 0.0, item.height, texture, {}, false});
      }
      addSegment(segment, decals);
    }
  }

  // Room grid for floor colours.
  const cv::Rect2d bounds = world_.bounds();
  grid_origin_ = Point(bounds.x - 1.0, bounds.y - 1.0);
  const int cols = static_cast<int>(std::ceil((bounds.width + 2.0) / grid_cell_));
  const int rows = static_cast<int>(std::ceil((bounds.height + 2.0) / grid_cell_));
  room_grid_ = cv::Mat::zeros(rows, cols, CV_8UC1);
  for (const Room& room : world_.rooms) {
    std::vector<cv::Point> cells;
    for (const Point& p : room.polygon) {
      cells.emplace_back(static_cast<int>(std::lround((p.x - grid_origin_.x) / grid_cell_)),
                         static_cast<int>(std::lround((p.y - grid_origin_.y) / grid_cell_)));
    }
    cv::fillPoly(room_grid_, std::vector<std::vector<cv::Point>>{cells}, cv::Scalar(std::min(room.id + 1, 255)));
  }
}

int Scene::floorRoom(const Point& p) const {
  const int col = static_cast<int>((p.x - grid_origin_.x) / grid_cell_);
  const int row = static_cast<int>((p.y - grid_origin_.y) / grid_cell_);
  if (col < 0 || row < 0 || col >= room_grid_.cols || row >= room_grid_.rows) return -1;
  return static_cast<int>(room_grid_.at<unsigned char>(row, col)) - 1;
}

}  // namespace toposlam::sim
