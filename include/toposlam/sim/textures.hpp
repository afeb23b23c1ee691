// Procedural textures for the simulated world, drawn once per object from a seed so the same poster
// looks the same on every visit: posters (random rectangles, text-like strokes, a checker patch),
// whiteboards (marker strokes), bookshelf fronts (shelf boards and books) and people (head, shirt,
// trousers). All CV_8UC3 BGR, row 0 = top of the object. Pure functions: thread-safe.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

namespace toposlam::sim {

inline constexpr double kTexturePixelsPerMetre = 160.0;

cv::Mat makePosterTexture(std::uint64_t seed, double width_m, double height_m);
cv::Mat makeBoardTexture(std::uint64_t seed, double width_m, double height_m);
cv::Mat makeShelfTexture(std::uint64_t seed, double width_m, double height_m, const cv::Vec3b& body_bgr);
cv::Mat makeDeskTexture(std::uint64_t seed, double width_m, double height_m, const cv::Vec3b& body_bgr);
cv::Mat makePersonTexture(std::uint64_t seed);

}  // namespace toposlam::sim
