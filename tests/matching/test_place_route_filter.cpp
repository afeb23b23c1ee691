// PlaceRouteFilter: one forward step of the route HMM per image, hand-computed cases, its edges, and
// what it is for (a misleading image on the way does not move the robot).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "toposlam/matching/place_route_filter.hpp"

using namespace toposlam;

namespace {

PlaceRouteFilterConfig config(double stay, double jump, bool loop) {
  PlaceRouteFilterConfig c;
  c.stay_probability = stay;
  c.jump_weight = jump;
  c.loop = loop;
  return c;
}

}  // namespace

SCENARIO("GIVEN three places on a loop WHEN two images arrive THEN the belief is the hand-computed HMM step",
         "[route]") {
  PlaceRouteFilter filter(config(0.6, 0.1, true), 3);
  const std::vector<double>& first = filter.update(std::vector<double>{0.5, 0.3, 0.2});
  // The first image has no prediction: its own probabilities.
  CHECK(first[0] == Approx(0.5));
  CHECK(first[1] == Approx(0.3));
  CHECK(first[2] == Approx(0.2));
  // Prediction: (0.1 + 0.6 b_k + 0.4 b_{k-1}) / 1.3 = (0.48, 0.48, 0.34) / 1.3; times (0.2, 0.2, 0.6).
  const std::vector<double>& second = filter.update(std::vector<double>{0.2, 0.2, 0.6});
  CHECK(second[0] == Approx(0.096 / 0.396));
  CHECK(second[1] == Approx(0.096 / 0.396));
  CHECK(second[2] == Approx(0.204 / 0.396));
  CHECK(second[0] + second[1] + second[2] == Approx(1.0));
}

SCENARIO(
    "GIVEN a route that is no loop WHEN the robot is at the last place THEN it stays there and the first "
    "place gets only the jump share",
    "[route]") {
  PlaceRouteFilter filter(config(0.6, 0.1, false), 3);
  filter.update(std::vector<double>{0.5, 0.3, 0.2});
  // Prediction: (0.4, 0.48, 0.42) / 1.3 (the last place keeps its "next" share); times (0.2, 0.2, 0.6).
  const std::vector<double>& b = filter.update(std::vector<double>{0.2, 0.2, 0.6});
  CHECK(b[0] == Approx(0.08 / 0.428));
  CHECK(b[1] == Approx(0.096 / 0.428));
  CHECK(b[2] == Approx(0.252 / 0.428));
}

SCENARIO(
    "GIVEN a robot walking the route WHEN one image on the way points to a far place THEN the filtered place "
    "stays right",
    "[route]") {
  PlaceRouteFilter filter(PlaceRouteFilterConfig{}, 5);
  // Two images at place 1, then a misleading one (place 4 by its own probabilities), then place 2.
  filter.update(std::vector<double>{0.1, 0.6, 0.1, 0.1, 0.1});
  filter.update(std::vector<double>{0.1, 0.6, 0.1, 0.1, 0.1});
  const std::vector<double>& misled = filter.update(std::vector<double>{0.05, 0.25, 0.1, 0.05, 0.55});
  const auto best = [](const std::vector<double>& b) {
    return std::max_element(b.begin(), b.end()) - b.begin();
  };
  CHECK(best(misled) == 1);
  const std::vector<double>& moved = filter.update(std::vector<double>{0.05, 0.2, 0.6, 0.1, 0.05});
  CHECK(best(moved) == 2);
  // Without the filter the misleading image alone would have said place 4; reset forgets the route.
  filter.reset();
  CHECK(best(filter.update(std::vector<double>{0.05, 0.25, 0.1, 0.05, 0.55})) == 4);
}

SCENARIO(
    "GIVEN an image with no usable evidence WHEN it is folded in THEN the belief is the prediction alone",
    "[route]") {
  PlaceRouteFilter filter(config(0.5, 0.0, true), 2);
  filter.update(std::vector<double>{1.0, 0.0});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double>& b = filter.update(std::vector<double>{0.0, nan});
  CHECK(b[0] == Approx(0.5));
  CHECK(b[1] == Approx(0.5));
}

SCENARIO("GIVEN bad input WHEN the filter is built or fed THEN it says what is wrong", "[route]") {
  CHECK_THROWS_WITH(PlaceRouteFilter(config(1.5, 0.01, true), 3),
                    Catch::Contains("stay_probability: must be in [0, 1]"));
  CHECK_THROWS_WITH(PlaceRouteFilter(config(0.7, -1.0, true), 3),
                    Catch::Contains("jump_weight: must be >= 0"));
  CHECK_THROWS_WITH(PlaceRouteFilter(PlaceRouteFilterConfig{}, 0), Catch::Contains("at least one place"));
  PlaceRouteFilter filter(PlaceRouteFilterConfig{}, 3);
  CHECK_THROWS_WITH(filter.update(std::vector<double>{0.5, 0.5}),
                    Catch::Contains("2 image probabilities for 3 places"));
}

SCENARIO("GIVEN a map's graph of successors WHEN an image arrives THEN the moving share is split over the edges by weight",
         "[route]") {
  // Node 0 leads to 1 (weight 3) and 2 (weight 1); node 1 has no successor (it keeps its share); 2 leads to 0.
  PlaceRouteFilter filter(config(0.5, 0.0, true), 3);
  filter.setSuccessors({{{1, 3.0}, {2, 1.0}}, {}, {{0, 1.0}}});
  filter.update(std::vector<double>{1.0, 0.0, 0.0});  // certain: node 0
  // Prediction from node 0: stay 0.5, to 1 0.5 * 3/4 = 0.375, to 2 0.125; the image is uniform.
  const std::vector<double>& b = filter.update(std::vector<double>{1.0, 1.0, 1.0});
  CHECK(b[0] == Approx(0.5));
  CHECK(b[1] == Approx(0.375));
  CHECK(b[2] == Approx(0.125));
  // From node 1 (no successor) the whole belief stays there.
  PlaceRouteFilter dead_end(config(0.5, 0.0, true), 3);
  dead_end.setSuccessors({{{1, 1.0}}, {}, {}});
  dead_end.update(std::vector<double>{0.0, 1.0, 0.0});
  CHECK(dead_end.update(std::vector<double>{1.0, 1.0, 1.0})[1] == Approx(1.0));
  // The share of staying can be changed between updates, within [0, 1].
  filter.setStayProbability(1.0);
  CHECK(filter.update(std::vector<double>{1.0, 1.0, 1.0})[0] == Approx(0.5));
  CHECK_THROWS_WITH(filter.setStayProbability(1.5), Catch::Contains("stay_probability"));
}

SCENARIO("GIVEN successors that do not fit WHEN they are set THEN they are refused by what is wrong", "[route]") {
  PlaceRouteFilter filter(PlaceRouteFilterConfig{}, 2);
  CHECK_THROWS_WITH(filter.setSuccessors({{}}), Catch::Contains("successors of 1 places for 2"));
  CHECK_THROWS_WITH(filter.setSuccessors({{{2, 1.0}}, {}}), Catch::Contains("successor 2 is not a place"));
  CHECK_THROWS_WITH(filter.setSuccessors({{{1, 0.0}}, {}}), Catch::Contains("positive and finite"));
  CHECK_THROWS_WITH(filter.setSuccessors({{{1, std::numeric_limits<double>::infinity()}}, {}}),
                    Catch::Contains("positive and finite"));
}
