// A top-down picture of a simulated world (rooms in their floor colour, walls, doors, furniture, posters)
// with a trajectory drawn over it, for `toposlam sim` output and the docs. Pure function: thread-safe.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "toposlam/sim/route.hpp"
#include "toposlam/sim/world.hpp"

namespace toposlam::sim {

/// BGR image, `pixels_per_metre` scale, y axis up; the route is drawn in colours that change with the
/// traversal, with a dot every `mark_every` poses (0 = none) and room names written in each room.
cv::Mat drawWorldMap(const World& world, const std::vector<Pose>& route, const std::vector<int>& traversal,
                     double pixels_per_metre = 40.0, int mark_every = 0);

}  // namespace toposlam::sim
