// Top-down drawing of a simulated world with a route over it (map_drawing.hpp).
#include "toposlam/sim/map_drawing.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace toposlam::sim {

cv::Mat drawWorldMap(const World& world, const std::vector<Pose>& route, const std::vector<int>& traversal,
                     double pixels_per_metre, int mark_every) {
  const cv::Rect2d bounds = world.bounds();
  const double margin = 0.6;
  const int width = static_cast<int>(std::ceil((bounds.width + 2 * margin) * pixels_per_metre));
  const int height = static_cast<int>(std::ceil((bounds.height + 2 * margin) * pixels_per_metre));
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  auto to_pixel = [&](const Point& p) {
    return cv::Point(static_cast<int>(std::lround((p.x - bounds.x + margin) * pixels_per_metre)),
                     static_cast<int>(std::lround((bounds.y + bounds.height + margin - p.y) * pixels_per_metre)));
  };
  for (const Room& room : world.rooms) {
    std::vector<cv::Point> corners;
    for (const Point& p : room.polygon) corners.push_back(to_pixel(p));
    const cv::Vec3b& floor = room.floor_bgr;
    const cv::Scalar light(128 + floor[0] / 2, 128 + floor[1] / 2, 128 + floor[2] / 2);
    cv::fillPoly(image, std::vector<std::vector<cv::Point>>{corners}, light);
  }
  for (const Room& room : world.rooms) {
    std::vector<cv::Point> corners;
    for (const Point& p : room.polygon) corners.push_back(to_pixel(p));
    cv::polylines(image, std::vector<std::vector<cv::Point>>{corners}, true,
                  cv::Scalar(room.wall_bgr[0] / 3, room.wall_bgr[1] / 3, room.wall_bgr[2] / 3), 3);
  }
  for (const Door& door : world.doors) {
    const Point half = door.along * (door.width / 2);
    cv::line(image, to_pixel(door.centre - half), to_pixel(door.centre + half), cv::Scalar(255, 255, 255), 4);
    cv::line(image, to_pixel(door.centre - half), to_pixel(door.centre + half), cv::Scalar(60, 80, 120), 1);
  }
  for (const Furniture& item : world.furniture) {
    const Point side(item.front.y, -item.front.x);
    const Point hw = side * (item.width / 2), hd = item.front * (item.depth / 2);
    std::vector<cv::Point> box = {to_pixel(item.centre - hw - hd), to_pixel(item.centre + hw - hd),
                                  to_pixel(item.centre + hw + hd), to_pixel(item.centre - hw + hd)};
    cv::fillPoly(image, std::vector<std::vector<cv::Point>>{box},
                 cv::Scalar(item.body_bgr[0], item.body_bgr[1], item.body_bgr[2]));
  }
  for (const WallDecor& decor : world.decor) {
    if (decor.kind == DecorKind::Sign) continue;  // too small to show
    const Room& room = world.rooms[static_cast<std::size_t>(decor.room)];
    const Point a = room.polygon[static_cast<std::size_t>(decor.edge)];
    const Point b = room.polygon[(static_cast<std::size_t>(decor.edge) + 1) % room.polygon.size()];
    const Point d = (b - a) * (1.0 / std::hypot(b.x - a.x, b.y - a.y));
    const Point inward(-d.y * 0.06, d.x * 0.06);
    cv::line(image, to_pixel(a + d * decor.u0 + inward), to_pixel(a + d * decor.u1 + inward),
             decor.kind == DecorKind::Poster ? cv::Scalar(30, 120, 230) : cv::Scalar(120, 120, 120), 3);
  }
  const cv::Scalar traversal_colours[] = {{200, 60, 20}, {30, 30, 210}, {30, 160, 30}, {160, 30, 160}};
  for (std::size_t i = 1; i < route.size(); ++i) {
    const int pass = i < traversal.size() ? traversal[i] : 0;
    const cv::Point offset(0, 3 * (pass % 3));  // later traversals drawn slightly apart
    cv::line(image, to_pixel({route[i - 1].x, route[i - 1].y}) + offset, to_pixel({route[i].x, route[i].y}) + offset,
             traversal_colours[pass % 4], 2, cv::LINE_AA);
    if (mark_every > 0 && i % static_cast<std::size_t>(mark_every) == 0) {
      cv::circle(image, to_pixel({route[i].x, route[i].y}) + offset, 3, traversal_colours[pass % 4], cv::FILLED);
    }
  }
  if (!route.empty()) {
    const cv::Point start = to_pixel({route.front().x, route.front().y});
    cv::circle(image, start, 6, cv::Scalar(0, 0, 0), 2);
    const Pose& first = route.front();
    cv::arrowedLine(image, start,
                    to_pixel({first.x + 0.8 * std::cos(first.heading), first.y + 0.8 * std::sin(first.heading)}),
                    cv::Scalar(0, 0, 0), 2);
  }
  for (const Room& room : world.rooms) {
    Point centre(0, 0);
    for (const Point& p : room.polygon) centre += p;
    centre *= 1.0 / static_cast<double>(room.polygon.size());
    const std::string label = std::to_string(room.id) + " " + room.name;
    cv::putText(image, label, to_pixel(centre) + cv::Point(-static_cast<int>(label.size()) * 4, 0),
                cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  return image;
}

}  // namespace toposlam::sim
