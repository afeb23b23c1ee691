// The simulated world behind the FrameSource interface (sim_source.hpp).
#include "toposlam/io/sim_source.hpp"

#include <cstdio>
#include <stdexcept>

namespace toposlam {

sim::SimConfig simConfigFromUri(const SourceUri& uri) {
  uri.requireOnly({"route", "fps", "size", "seed", "speed", "fov", "light", "noise", "people", "pitch", "moved"});
  sim::SimConfig config;
  if (uri.path.empty()) throw FrameSourceError("source '" + uri.text + "': sim: needs a world, e.g. sim:office or sim:home");
  config.world = uri.path;
  config.route = uri.getString("route", config.route);
  config.fps = uri.getDouble("fps", config.fps, 0.1, 1000);
  const auto [width, height] = uri.getSize("size", {config.camera.width, config.camera.height}, 16, 4096);
  config.camera.width = width;
  config.camera.height = height;
  config.camera.horizontal_fov_deg = uri.getDouble("fov", config.camera.horizontal_fov_deg, 20, 150);
  config.seed = static_cast<std::uint64_t>(uri.getInt("seed", static_cast<long long>(config.seed), 0, 1LL << 53));
  config.motion.speed = uri.getDouble("speed", config.motion.speed, 0.02, 5);
  config.lighting = sim::parseLightingMode(uri.getChoice("light", "day", {"day", "night", "warm", "cool"}));
  config.noise_sigma = uri.getDouble("noise", config.noise_sigma, 0, 50);
  config.people = static_cast<int>(uri.getInt("people", config.people, 0, 20));
  config.pitch_deg = uri.getDouble("pitch", config.pitch_deg, 0, 10);
  config.moved_furniture = uri.getBool("moved", config.moved_furniture);
  return config;
}

SimFrameSource::SimFrameSource(const sim::SimConfig& config) {
  try {
    simulator_ = std::make_unique<sim::Simulator>(config);
  } catch (const std::invalid_argument& e) {
    throw FrameSourceError(std::string("sim: ") + e.what());
  }
}

std::string SimFrameSource::describe() const {
  const sim::SimConfig& config = simulator_->config();
  char text[256];
  std::snprintf(text, sizeof text, "sim:%s route %s, %dx%d at %g fps, seed %llu (%lld frames)", config.world.c_str(),
                config.route.c_str(), config.camera.width, config.camera.height, config.fps,
                static_cast<unsigned long long>(config.seed), static_cast<long long>(simulator_->frameCount()));
  return text;
}

std::optional<Frame> SimFrameSource::next() {
  if (interrupted_.load()) return std::nullopt;
  std::optional<sim::SimFrame> rendered = simulator_->next();
  if (!rendered) return std::nullopt;
  last_truth_ = rendered->truth;
  Frame frame;
  frame.image = std::move(rendered->image);
  frame.sequence = rendered->truth.frame;
  frame.timestamp_s = rendered->truth.time_s;
  char name[32];
  std::snprintf(name, sizeof name, "%06lld.png", static_cast<long long>(rendered->truth.frame));
  frame.name = name;
  return frame;
}

}  // namespace toposlam
