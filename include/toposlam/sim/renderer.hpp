// A 2.5-D ray caster for the simulated world: one ray per image column against the wall segments
// (walls face into their room and are culled from behind; furniture and people are partial-height
// segments drawn back to front), then per-row shading of wall, floor and ceiling. Walls are lit by a
// fixed direction (so corners show as vertical edges) and fade with distance; floors get a per-room
// pattern and ceilings a grid of lights. Perspective pinhole camera with no roll; pitch is a vertical
// shift of the horizon (exact for small pitch in a ray caster).
//
// Scene is the compiled, immutable form of a World (segments, textures, a room grid for floors).
// Renderer::render is const and allocation-light; one Renderer per thread.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "toposlam/sim/route.hpp"
#include "toposlam/sim/world.hpp"

namespace toposlam::sim {

struct Decal {
  double u0 = 0, u1 = 0, v0 = 0, v1 = 0;  ///< metres along the segment's parent edge / above floor
  int texture = -1;                       ///< index into Scene::textures, or -1 for the solid colour
  cv::Vec3b bgr{0, 0, 0};                 ///< colour when texture == -1
  bool transparent = false;               ///< texels equal to (1, 1, 1) let what is behind show
};

struct Segment {
  Point a, b;                 ///< visible from the left of a -> b (the side its normal points to)
  double bottom = 0, top = 0; ///< metres above the floor
  cv::Vec3b bgr;
  double u_at_a = 0;          ///< u coordinate of a (decals use the parent edge's u)
  int decal_begin = 0, decal_end = 0;  ///< range into Scene::decals
  bool full_height = false;   ///< true for room walls: occludes everything behind it
  double light = 1.0;         ///< Lambert factor from its orientation (precomputed)
};

class Scene {
 public:
  explicit Scene(const World& world);
  /// Same world with different furniture (the "moved furniture" variation).
  Scene(const World& world, const std::vector<Furniture>& furniture);

  const World& world() const { return world_; }
  const std::vector<Segment>& segments() const { return segments_; }
  const std::vector<Decal>& decals() const { return decals_; }
  const std::vector<cv::Mat>& textures() const { return textures_; }
  /// Room id of the floor at p (grid lookup, 5 cm cells), -1 outside.
  int floorRoom(const Point& p) const;

 private:
  void compile(const std::vector<Furniture>& furniture);
  void addSegment(Segment segment, const std::vector<Decal>& decals);
  World world_;
  std::vector<Segment> segments_;
  std::vector<Decal> decals_;
  std::vector<cv::Mat> textures_;
  cv::Mat room_grid_;  ///< CV_8UC1, room id + 1 per cell (0 = outside)
  cv::Point2d grid_origin_;
  double grid_cell_ = 0.05;
};

struct CameraConfig {
  int width = 320, height = 240;    ///< pixels
  double horizontal_fov_deg = 60.0;
  double height_m = 1.0;            ///< camera height above the floor
  std::string validate() const;
};

/// A moving occluder (a person), drawn as a billboard facing the camera.
struct Billboard {
  Point centre;
  double width = 0.5, height = 1.7;  ///< metres
  int texture = -1;                  ///< index into the `textures` argument of render()
};

struct Lighting {
  cv::Vec3f gain{1.f, 1.f, 1.f};  ///< per channel (B, G, R) multiplier applied to the whole frame
  double distance_falloff = 0.015; ///< attenuation 1 / (1 + k z^2), z in metres
};

class Renderer {
 public:
  explicit Renderer(const CameraConfig& camera);
  const CameraConfig& camera() const { return camera_; }
  double focalPixels() const { return focal_; }
  /// Renders into `out` (resized to CV_8UC3 width x height). pitch_rad > 0 looks up.
  void render(const Scene& scene, const Pose& pose, double pitch_rad, const Lighting& lighting,
              const std::vector<Billboard>& billboards, const std::vector<cv::Mat>& billboard_textures,
              cv::Mat& out) const;
  /// Image column (pixels, may be outside the image) where world point p projects; NaN if behind.
  double projectColumn(const Pose& pose, const Point& p) const;

 private:
  CameraConfig camera_;
  double focal_;
};

}  // namespace toposlam::sim
