// The 2.5-D ray caster (see renderer.hpp). Per image column: intersect one ray with every segment, keep
// the nearest full-height wall and the partial-height things in front of it; then shade the column top
// to bottom (ceiling, wall, floor) and paint the partial things over it, far to near.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "toposlam/sim/renderer.hpp"

namespace toposlam::sim {

namespace {

constexpr double kNearClip = 0.05;  // metres
constexpr int kMaxPartialHits = 12;

struct Hit {
  double z = 0;            // forward depth (metres)
  double u = 0;            // along the segment's parent edge (metres)
  const Segment* segment = nullptr;
  const Decal* decals = nullptr;           // the segment's decals
  int decal_count = 0;
  const std::vector<cv::Mat>* textures = nullptr;
};

inline std::uint32_t hashCell(int x, int y) {
  std::uint32_t h = static_cast<std::uint32_t>(x) * 374761393u + static_cast<std::uint32_t>(y) * 668265263u;
  h = (h ^ (h >> 13)) * 1274126177u;
  return h ^ (h >> 16);
}

inline cv::Vec3b shade(const cv::Vec3b& colour, int factor_q8) {
  return {static_cast<unsigned char>(std::min(255, (colour[0] * factor_q8) >> 8)),
          static_cast<unsigned char>(std::min(255, (colour[1] * factor_q8) >> 8)),
          static_cast<unsigned char>(std::min(255, (colour[2] * factor_q8) >> 8))};
}

inline int attenuationQ8(double z, double falloff, double light) {
  const double factor = std::max(0.3, light / (1.0 + falloff * z * z));
  return static_cast<int>(factor * 256.0);
}

inline double positiveMod(double value, double period) {
  const double r = std::fmod(value, period);
  return r < 0 ? r + period : r;
}

cv::Vec3b floorColour(const Scene& scene, const Point& p) {
  const int room_id = scene.floorRoom(p);
  if (room_id < 0) return {50, 50, 50};
  const Room& room = scene.world().rooms[static_cast<std::size_t>(room_id)];
  cv::Vec3b colour = room.floor_bgr;
  switch (room.floor_pattern) {
    case FloorPattern::Carpet: {
      const int noise = static_cast<int>(hashCell(static_cast<int>(std::floor(p.x * 25)),
                                                  static_cast<int>(std::floor(p.y * 25))) % 9) - 4;
      for (int c = 0; c < 3; ++c) colour[c] = cv::saturate_cast<unsigned char>(colour[c] + noise);
      break;
    }
    case FloorPattern::Tiles: {
      if (positiveMod(p.x, 0.5) < 0.02 || positiveMod(p.y, 0.5) < 0.02) colour = colour * 0.7;
      break;
    }
    case FloorPattern::Wood: {
      const int plank = static_cast<int>(std::floor(p.y / 0.16));
      const double offset = (hashCell(plank, 7) % 100) * 0.012;
      if (positiveMod(p.y, 0.16) < 0.012 || positiveMod(p.x + offset, 1.2) < 0.01) {
        colour = colour * 0.6;
      } else {
        const int tone = static_cast<int>(hashCell(plank, static_cast<int>(std::floor((p.x + offset) / 1.2))) % 21) - 10;
        for (int c = 0; c < 3; ++c) colour[c] = cv::saturate_cast<unsigned char>(colour[c] + tone);
      }
      break;
    }
  }
  return colour;
}

cv::Vec3b ceilingColour(const World& world, const Point& p) {
  const double gx = positiveMod(p.x, 2.4), gy = positiveMod(p.y, 2.4);
  if (gx > 0.9 && gx < 1.5 && gy > 0.75 && gy < 1.65) return {252, 252, 252};  // light panel
  if (positiveMod(p.x, 0.6) < 0.015 || positiveMod(p.y, 0.6) < 0.015) return world.ceiling_bgr * 0.88;
  return world.ceiling_bgr;
}

}  // namespace

std::string CameraConfig::validate() const {
  if (width < 16 || width > 4096) return "size: width must be in 16..4096 pixels";
  if (height < 16 || height > 4096) return "size: height must be in 16..4096 pixels";
  if (!(horizontal_fov_deg >= 20 && horizontal_fov_deg <= 150)) return "fov: must be in 20..150 degrees";
  if (!(height_m > 0.1 && height_m < 2.0)) return "camera_height: must be in (0.1, 2.0) metres";
  return "";
}

Renderer::Renderer(const CameraConfig& camera)
    : camera_(camera), focal_(camera.width / 2.0 / std::tan(camera.horizontal_fov_deg * std::numbers::pi / 360.0)) {}

double Renderer::projectColumn(const Pose& pose, const Point& p) const {
  const Point forward(std::cos(pose.heading), std::sin(pose.heading));
  const Point right(std::sin(pose.heading), -std::cos(pose.heading));
  const Point offset = p - Point(pose.x, pose.y);
  const double z = offset.dot(forward);
  if (z <= kNearClip) return std::numeric_limits<double>::quiet_NaN();
  return camera_.width / 2.0 + focal_ * offset.dot(right) / z;
}

void Renderer::render(const Scene& scene, const Pose& pose, double pitch_rad, const Lighting& lighting,
                      const std::vector<Billboard>& billboards, const std::vector<cv::Mat>& billboard_textures,
                      cv::Mat& out) const {
  const int width = camera_.width, height = camera_.height;
  out.create(height, width, CV_8UC3);
  const World& world = scene.world();
  const double cam_h = camera_.height_m;
  const double wall_h = world.wall_height;
  const Point camera(pose.x, pose.y);
  const Point forward(std::cos(pose.heading), std::sin(pose.heading));
  const Point right(std::sin(pose.heading), -std::cos(pose.heading));
  const double horizon = height / 2.0 + focal_ * std::tan(pitch_rad);

  // Per row: slope (height above the camera per metre of depth), floor and ceiling depth.
  std::vector<double> slope(static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) slope[static_cast<std::size_t>(y)] = (horizon - (y + 0.5)) / focal_;

  // People: billboards facing the camera, with transparent texels.
  std::vector<Segment> people;
  std::vector<Decal> people_decals;
  people.reserve(billboards.size());
  people_decals.reserve(billboards.size());
  for (const Billboard& person : billboards) {
    Point towards = person.centre - camera;
    const double distance = std::hypot(towards.x, towards.y);
    if (distance < 0.3) continue;
    towards *= 1.0 / distance;
    const Point viewer_right(towards.y, -towards.x);
    Segment segment;
    segment.a = person.centre + viewer_right * (person.width / 2);
    segment.b = person.centre - viewer_right * (person.width / 2);
    segment.top = person.height;
    segment.light = 0.95;
    segment.decal_begin = static_cast<int>(people_decals.size());
    segment.decal_end = segment.decal_begin + 1;
    people_decals.push_back({0.0, person.width, 0.0, person.height, person.texture, {}, true});
    people.push_back(segment);
  }

  const std::vector<cv::Mat>& scene_textures = scene.textures();
  std::array<Hit, kMaxPartialHits> partial{};
  for (int x = 0; x < width; ++x) {
    const double column = (x + 0.5 - width / 2.0) / focal_;
    const Point dir = forward + right * column;  // forward component 1: t is the depth z
    Hit wall;
    wall.z = std::numeric_limits<double>::max();
    int partial_count = 0;
    auto intersect = [&](const Segment& segment, const std::vector<Decal>& decals,
                         const std::vector<cv::Mat>* textures) {
      const Point e = segment.b - segment.a;
      const double denom = dir.x * e.y - dir.y * e.x;
      if (denom <= 1e-12) return;  // parallel, or seen from behind
      const Point w = segment.a - camera;
      const double t = (w.x * e.y - w.y * e.x) / denom;
      if (t < kNearClip || t >= wall.z) return;
      const double s = (w.x * dir.y - w.y * dir.x) / denom;
      if (s < 0.0 || s > 1.0) return;
      Hit hit;
      hit.z = t;
      hit.u = segment.u_at_a + s * std::hypot(e.x, e.y);
      hit.segment = &segment;
      hit.decals = decals.data() + segment.decal_begin;
      hit.decal_count = segment.decal_end - segment.decal_begin;
      hit.textures = textures;
      if (segment.full_height) {
        wall = hit;
      } else if (partial_count < kMaxPartialHits) {
        partial[static_cast<std::size_t>(partial_count++)] = hit;
      } else {  // replace the farthest
        auto farthest = std::max_element(partial.begin(), partial.end(),
                                         [](const Hit& l, const Hit& r) { return l.z < r.z; });
        if (farthest->z > t) *farthest = hit;
      }
    };
    for (const Segment& segment : scene.segments()) intersect(segment, scene.decals(), &scene_textures);
    for (const Segment& segment : people) intersect(segment, people_decals, &billboard_textures);

    // Draws rows of one hit; returns nothing. Rows outside [bottom, top] of the segment are left alone.
    auto draw_hit = [&](const Hit& hit) {
      const Segment& segment = *hit.segment;
      const double z = hit.z;
      const int first = std::max(0, static_cast<int>(std::ceil(horizon - 0.5 - focal_ * (segment.top - cam_h) / z)));
      const int last = std::min(height, static_cast<int>(std::floor(horizon - 0.5 - focal_ * (segment.bottom - cam_h) / z)) + 1);
      if (first >= last) return;
      const int factor = attenuationQ8(z, lighting.distance_falloff, segment.light);
      // Decals covering this u, with the texture column they sample.
      std::array<const Decal*, 6> active{};
      std::array<int, 6> texture_column{};
      int active_count = 0;
      for (int i = 0; i < hit.decal_count && active_count < 6; ++i) {
        const Decal& decal = hit.decals[i];
        if (hit.u < decal.u0 || hit.u > decal.u1) continue;
        active[static_cast<std::size_t>(active_count)] = &decal;
        if (decal.texture >= 0) {
          const cv::Mat& texture = (*hit.textures)[static_cast<std::size_t>(decal.texture)];
          // u grows to the viewer's left, so the texture is mirrored (see Segment).
          const int tx = static_cast<int>((decal.u1 - hit.u) / (decal.u1 - decal.u0) * texture.cols);
          texture_column[static_cast<std::size_t>(active_count)] = std::clamp(tx, 0, texture.cols - 1);
        }
        ++active_count;
      }
      for (int y = first; y < last; ++y) {
        const double v = cam_h + slope[static_cast<std::size_t>(y)] * z;
        cv::Vec3b colour = segment.bgr;
        bool transparent = false;
        for (int i = active_count - 1; i >= 0; --i) {
          const Decal& decal = *active[static_cast<std::size_t>(i)];
          if (v < decal.v0 || v > decal.v1) continue;
          if (decal.texture < 0) {
            colour = decal.bgr;
          } else {
            const cv::Mat& texture = (*hit.textures)[static_cast<std::size_t>(decal.texture)];
            const int ty = std::clamp(static_cast<int>((decal.v1 - v) / (decal.v1 - decal.v0) * texture.rows), 0,
                                      texture.rows - 1);
            colour = texture.at<cv::Vec3b>(ty, texture_column[static_cast<std::size_t>(i)]);
            transparent = decal.transparent && colour == cv::Vec3b(1, 1, 1);
          }
          break;
        }
        if (!transparent) out.at<cv::Vec3b>(y, x) = shade(colour, factor);
      }
    };

    // Ceiling and floor everywhere the wall does not cover, then the wall, then partial things.
    int wall_first = height, wall_last = height;
    if (wall.segment != nullptr) {
      wall_first = std::clamp(static_cast<int>(std::ceil(horizon - 0.5 - focal_ * (wall_h - cam_h) / wall.z)), 0, height);
      wall_last = std::clamp(static_cast<int>(std::floor(horizon - 0.5 + focal_ * cam_h / wall.z)) + 1, 0, height);
    } else {
      wall_first = wall_last = std::clamp(static_cast<int>(horizon), 0, height);
    }
    for (int y = 0; y < wall_first; ++y) {
      const double k = slope[static_cast<std::size_t>(y)];
      if (k <= 1e-6) {
        out.at<cv::Vec3b>(y, x) = world.ceiling_bgr * 0.3;
        continue;
      }
      const double z = (wall_h - cam_h) / k;
      const Point p = camera + dir * z;
      out.at<cv::Vec3b>(y, x) = shade(ceilingColour(world, p), attenuationQ8(z, lighting.distance_falloff, 1.0));
    }
    for (int y = wall_last; y < height; ++y) {
      const double k = slope[static_cast<std::size_t>(y)];
      if (k >= -1e-6) {
        out.at<cv::Vec3b>(y, x) = cv::Vec3b(40, 40, 40);
        continue;
      }
      const double z = cam_h / -k;
      const Point p = camera + dir * z;
      out.at<cv::Vec3b>(y, x) = shade(floorColour(scene, p), attenuationQ8(z, lighting.distance_falloff, 0.9));
    }
    if (wall.segment != nullptr) draw_hit(wall);
    // Partial things found before the nearest wall was known may stand behind it.
    partial_count = static_cast<int>(std::remove_if(partial.begin(), partial.begin() + partial_count,
                                                    [&](const Hit& hit) { return hit.z >= wall.z; }) -
                                     partial.begin());
    std::sort(partial.begin(), partial.begin() + partial_count, [](const Hit& l, const Hit& r) { return l.z > r.z; });
    for (int i = 0; i < partial_count; ++i) draw_hit(partial[static_cast<std::size_t>(i)]);
  }

  if (lighting.gain != cv::Vec3f(1.f, 1.f, 1.f)) {
    cv::Mat table(1, 256, CV_8UC3);
    for (int level = 0; level < 256; ++level) {
      for (int c = 0; c < 3; ++c) table.at<cv::Vec3b>(0, level)[c] = cv::saturate_cast<unsigned char>(level * lighting.gain[c]);
    }
    cv::LUT(out, table, out);
  }
}

}  // namespace toposlam::sim
