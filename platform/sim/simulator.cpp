// The simulated camera: world + route + variation switches -> frames and ground truth (simulator.hpp).
#include "toposlam/sim/simulator.hpp"

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>

#include "toposlam/sim/floor_plan.hpp"
#include "toposlam/sim/textures.hpp"

namespace toposlam::sim {

namespace {

struct Walker {
  Point from, to;
  double speed = 0.7;  // m/s
  double phase = 0;    // seconds
};

Point walkerPosition(const Walker& walker, double time_s) {
  const double length = std::hypot(walker.to.x - walker.from.x, walker.to.y - walker.from.y);
  if (length < 1e-6) return walker.from;
  const double travelled = std::fmod((time_s + walker.phase) * walker.speed, 2 * length);
  const double f = travelled < length ? travelled / length : 2.0 - travelled / length;
  return walker.from + (walker.to - walker.from) * f;
}

Lighting lightingFor(LightingMode mode) {
  Lighting lighting;
  switch (mode) {
    case LightingMode::Day: break;
    case LightingMode::Night:
      lighting.gain = {0.42f, 0.5f, 0.58f};
      lighting.distance_falloff = 0.06;
      break;
    case LightingMode::Warm: lighting.gain = {0.85f, 0.96f, 1.08f}; break;
    case LightingMode::Cool: lighting.gain = {1.08f, 1.0f, 0.9f}; break;
  }
  return lighting;
}

}  // namespace

const char* toString(LightingMode mode) {
  switch (mode) {
    case LightingMode::Day: return "day";
    case LightingMode::Night: return "night";
    case LightingMode::Warm: return "warm";
    case LightingMode::Cool: return "cool";
  }
  return "day";
}

LightingMode parseLightingMode(const std::string& name) {
  if (name == "day") return LightingMode::Day;
  if (name == "night") return LightingMode::Night;
  if (name == "warm") return LightingMode::Warm;
  if (name == "cool") return LightingMode::Cool;
  throw std::invalid_argument("light: '" + name + "' is not a lighting mode; allowed: day, night, warm, cool");
}

std::string SimConfig::validate() const {
  if (world.empty()) return "world: empty; allowed: office, home, or a path to a .yaml floor plan";
  if (route.empty()) return "route: empty";
  if (!(fps > 0.01 && fps <= 1000)) return "fps: must be in (0.01, 1000] frames per simulated second";
  if (const std::string problem = camera.validate(); !problem.empty()) return problem;
  if (const std::string problem = motion.validate(); !problem.empty()) return problem;
  if (!(noise_sigma >= 0 && noise_sigma <= 50)) return "noise: must be in 0..50 grey levels";
  if (people < 0 || people > 20) return "people: must be in 0..20";
  if (!(pitch_deg >= 0 && pitch_deg <= 10)) return "pitch: must be in 0..10 degrees";
  return "";
}

struct Simulator::Variation {
  std::unique_ptr<Scene> scene;
  std::unique_ptr<Scene> moved_scene;  // null unless moved_furniture
  std::vector<Walker> walkers;
  std::vector<cv::Mat> person_textures;
  Lighting lighting;
  double pitch_phase = 0;
};

Simulator::Simulator(const SimConfig& config) : config_(config), renderer_(config.camera) {
  if (const std::string problem = config_.validate(); !problem.empty()) throw std::invalid_argument(problem);
  World world = loadWorld(config_.world);
  decorate(world, config_.seed);
  trajectory_ = buildTrajectory(world, config_.route, config_.motion, config_.seed);
  frame_count_ = static_cast<std::int64_t>(std::floor(trajectory_.duration() * config_.fps + 1e-9)) + 1;

  variation_ = std::make_unique<Variation>();
  variation_->lighting = lightingFor(config_.lighting);
  std::mt19937_64 rng(config_.seed * 0xD1B54A32D192ED03ULL + 17);
  variation_->pitch_phase = std::uniform_real_distribution<double>(0, 2 * std::numbers::pi)(rng);
  if (config_.moved_furniture) {
    variation_->moved_scene = std::make_unique<Scene>(world, moveFurniture(world, config_.seed));
  }
  // People walk back and forth between two random points of a random room.
  std::vector<double> areas;
  for (const Room& room : world.rooms) areas.push_back(signedArea(room.polygon));
  std::discrete_distribution<int> pick_room(areas.begin(), areas.end());
  for (int i = 0; i < config_.people; ++i) {
    const Room& room = world.rooms[static_cast<std::size_t>(pick_room(rng))];
    cv::Rect2d box(room.polygon.front(), room.polygon.front());
    for (const Point& corner : room.polygon) box |= cv::Rect2d(corner, corner);
    auto random_point = [&] {
      for (int attempt = 0; attempt < 100; ++attempt) {
        const Point p(std::uniform_real_distribution<double>(box.x + 0.5, box.x + box.width - 0.5)(rng),
                      std::uniform_real_distribution<double>(box.y + 0.5, box.y + box.height - 0.5)(rng));
        if (polygonContains(room.polygon, p)) return p;
      }
      return room.polygon.front();
    };
    Walker walker;
    walker.from = random_point();
    walker.to = random_point();
    walker.speed = std::uniform_real_distribution<double>(0.5, 1.0)(rng);
    walker.phase = std::uniform_real_distribution<double>(0, 30)(rng);
    variation_->walkers.push_back(walker);
    variation_->person_textures.push_back(makePersonTexture(rng()));
  }
  variation_->scene = std::make_unique<Scene>(std::move(world));
}

Simulator::~Simulator() = default;

const World& Simulator::world() const { return variation_->scene->world(); }

GroundTruth Simulator::truthOf(std::int64_t frame) const {
  GroundTruth truth;
  truth.frame = frame;
  truth.time_s = static_cast<double>(frame) / config_.fps;
  truth.pose = trajectory_.poseAt(truth.time_s);
  truth.room = world().placeLabel(Point(truth.pose.x, truth.pose.y));
  truth.traversal = trajectory_.traversalAt(truth.time_s);
  return truth;
}

SimFrame Simulator::render(std::int64_t frame) const {
  if (frame < 0 || frame >= frame_count_) {
    throw std::out_of_range("frame " + std::to_string(frame) + " outside 0.." + std::to_string(frame_count_ - 1));
  }
  SimFrame result;
  result.truth = truthOf(frame);
  const double t = result.truth.time_s;
  const Scene& scene =
      (variation_->moved_scene && result.truth.traversal >= 1) ? *variation_->moved_scene : *variation_->scene;
  const double pitch = config_.pitch_deg * std::numbers::pi / 180.0 *
                       (0.7 * std::sin(2 * std::numbers::pi * t / 2.7 + variation_->pitch_phase) +
                        0.3 * std::sin(2 * std::numbers::pi * t / 0.9 + 2 * variation_->pitch_phase));
  std::vector<Billboard> people;
  for (std::size_t i = 0; i < variation_->walkers.size(); ++i) {
    people.push_back({walkerPosition(variation_->walkers[i], t), 0.5, 1.7, static_cast<int>(i)});
  }
  renderer_.render(scene, result.truth.pose, pitch, variation_->lighting, people, variation_->person_textures,
                   result.image);
  if (config_.noise_sigma > 0) {
    cv::RNG rng(config_.seed * 1000003ULL + static_cast<std::uint64_t>(frame) + 1);
    cv::Mat noise(result.image.size(), CV_16SC3);
    rng.fill(noise, cv::RNG::NORMAL, cv::Scalar::all(0), cv::Scalar::all(config_.noise_sigma));
    cv::Mat widened;
    result.image.convertTo(widened, CV_16SC3);
    widened += noise;
    widened.convertTo(result.image, CV_8UC3);
  }
  return result;
}

std::optional<SimFrame> Simulator::next() {
  if (next_frame_ >= frame_count_) return std::nullopt;
  return render(next_frame_++);
}

cv::Mat loopClosureMatrix(const std::vector<int>& labels, int min_gap) {
  const int n = static_cast<int>(labels.size());
  cv::Mat matrix = cv::Mat::zeros(n, n, CV_8UC1);
  for (int i = 0; i < n; ++i) {
    if (labels[static_cast<std::size_t>(i)] < 0) continue;
    for (int j = 0; j < i - min_gap; ++j) {
      if (labels[static_cast<std::size_t>(j)] == labels[static_cast<std::size_t>(i)]) matrix.at<unsigned char>(i, j) = 255;
    }
  }
  return matrix;
}

}  // namespace toposlam::sim
