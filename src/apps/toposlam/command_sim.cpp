// `toposlam sim WORLD --route R --out DIR`: renders a route through a simulated world and writes the
// frames (frames/000000.png ...), the ground truth (labels.csv: frame,time,room,x,y,heading,traversal), the
// loop-closure matrix of the labels (loop_closure.png, laid out like samples_GT.bmp) and a top-down map
// of the world with the route (map.png), and the robot's own motion as wheel odometry would give it
// (motion.csv: time_s,distance_m,speed_mps,turn_rate_rps per frame; `map --motion`). Rendering speed: `toposlam-bench sim`.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numbers>
#include <set>
#include <stdexcept>


#include "commands.hpp"
#include "progress.hpp"
#include "toposlam/core/json_writer.hpp"
#include "offline_run_io.hpp"
#include "toposlam/run_folder/run_folder.hpp"
#include "toposlam/io/source_uri.hpp"
#include "toposlam/sim/floor_plan.hpp"
#include "toposlam/sim/map_drawing.hpp"
#include "toposlam/sim/simulator.hpp"

namespace toposlam::cli {

namespace {

struct SimOptions {
  std::string world = "office";
  std::string route = "loop";
  std::string out;
  double fps = 5.0;
  std::string size = "320x240";
  std::uint64_t seed = 1;
  double speed = 0.5;
  double fov = 60.0;
  std::string light = "day";
  double noise = 0.0;
  int people = 0;
  double pitch = 0.0;
  bool moved = false;
  int progress_every = 200;  ///< 0: no progress line (other values: a progress line, see progress.hpp)
  bool json = false;
};

sim::SimConfig toConfig(const SimOptions& options) {
  sim::SimConfig config;
  config.world = options.world;
  config.route = options.route;
  config.fps = options.fps;
  // Reuse the URI size parser so the CLI and sim: URIs accept and reject the same sizes.
  const SourceUri size_holder{"--size " + options.size, "", "", {{"size", options.size}}};
  const auto [width, height] = size_holder.getSize("size", {320, 240}, 16, 4096);
  config.camera.width = width;
  config.camera.height = height;
  config.camera.horizontal_fov_deg = options.fov;
  config.seed = options.seed;
  config.motion.speed = options.speed;
  config.lighting = sim::parseLightingMode(options.light);
  config.noise_sigma = options.noise;
  config.people = options.people;
  config.pitch_deg = options.pitch;
  config.moved_furniture = options.moved;
  if (const std::string problem = config.validate(); !problem.empty()) throw std::invalid_argument(problem);
  return config;
}

void runSim(const SimOptions& options) {
  const sim::SimConfig config = toConfig(options);
  const sim::Simulator simulator(config);
  if (options.out.empty()) throw std::invalid_argument("--out: give the folder to write frames and labels.csv into");
  namespace fs = std::filesystem;
  const fs::path out(options.out);
  std::error_code error;
  fs::create_directories(out / "frames", error);
  if (error) throw std::runtime_error("--out: cannot create '" + (out / "frames").string() + "': " + error.message());
  // Every file goes through an OutputFile (temporary name, checked, renamed): a full disk is an error
  // naming the file (exit 1), never "wrote".
  OutputFile labels(out / run_files::kLabels);
  labels << labelsHeader();
  // The frames' capture times, read back by images: sources (the segmentation window is in seconds).
  OutputFile timestamps(out / "frames" / "timestamps.csv");
  timestamps << "name,time_s\n";
  // The robot's own motion as its wheel odometry would report it, one sample per frame: distance driven
  // since the previous frame and the mean speed over it (read by `map --motion`; docs/segmentation.md).
  OutputFile motion(out / "motion.csv");
  motion << "time_s,distance_m,speed_mps,turn_rate_rps\n";
  double previous_time_s = 0.0;
  std::vector<sim::Pose> poses;
  std::vector<int> traversals, rooms;
  const std::int64_t frames = simulator.frameCount();
  std::cerr << "sim: " << frames << " frames of " << config.world << " route " << config.route << " into "
            << out.string() << "\n";
  Progress progress("sim", "frames", frames, options.progress_every == 0);
  for (std::int64_t i = 0; i < frames; ++i) {
    progress.update(i + 1);
    const sim::SimFrame frame = simulator.render(i);
    char name[32];
    std::snprintf(name, sizeof name, "%06lld.png", static_cast<long long>(i));
    writeImageFile(out / "frames" / name, frame.image);
    LabelRow label;
    label.frame = i;
    label.time_s = frame.truth.time_s;
    label.room = frame.truth.room;
    label.x = frame.truth.pose.x;
    label.y = frame.truth.pose.y;
    label.heading = frame.truth.pose.heading;
    label.traversal = frame.truth.traversal;
    labels << labelsRow(label);
    char stamp[64];
    std::snprintf(stamp, sizeof stamp, "%s,%.6f\n", name, frame.truth.time_s);
    timestamps << stamp;
    {
      const double step_m =
          poses.empty() ? 0.0 : std::hypot(frame.truth.pose.x - poses.back().x, frame.truth.pose.y - poses.back().y);
      const double dt = frame.truth.time_s - previous_time_s;
      const double turn_rad =
          poses.empty() ? 0.0 : std::remainder(frame.truth.pose.heading - poses.back().heading, 2.0 * std::numbers::pi);
      const bool rate = !poses.empty() && dt > 0.0;
      char sample[128];
      std::snprintf(sample, sizeof sample, "%.6f,%.6f,%.6f,%.6f\n", frame.truth.time_s, step_m, rate ? step_m / dt : 0.0,
                    rate ? std::abs(turn_rad) / dt : 0.0);
      motion << sample;
      previous_time_s = frame.truth.time_s;
    }
    poses.push_back(frame.truth.pose);
    traversals.push_back(frame.truth.traversal);
    rooms.push_back(frame.truth.room);
  }
  progress.finish();
  labels.commit();
  timestamps.commit();
  motion.commit();
  writeImageFile(out / "loop_closure.png", sim::loopClosureMatrix(rooms));
  writeImageFile(out / "map.png",
                 sim::drawWorldMap(simulator.world(), poses, traversals, 40.0, static_cast<int>(config.fps * 5)));
  std::cerr << "sim: wrote " << frames << " frames, labels.csv, motion.csv, loop_closure.png and map.png to " << out.string()
            << "\n";
  if (options.json) {
    int rooms_seen = 0;
    for (int room : std::set<int>(rooms.begin(), rooms.end())) rooms_seen += room >= 0 ? 1 : 0;
    JsonWriter json(std::cout);
    json.beginObject()
        .field("frames", frames)
        .field("seconds", previous_time_s)
        .field("traversals", traversals.empty() ? 0 : traversals.back() + 1)
        .field("rooms", rooms_seen)
        .field("width", config.camera.width)
        .field("height", config.camera.height)
        .field("out", out.string())
        .endObject();
    std::cout << "\n" << std::flush;
  }
}

}  // namespace

void addSimCommand(CLI::App& app) {
  auto options = std::make_shared<SimOptions>();
  auto* cmd = app.add_subcommand("sim", "Render a route through a simulated indoor world, with ground truth");
  cmd->add_option("world", options->world, "office | home | path to a YAML floor plan")->capture_default_str();
  cmd->add_option("--route", options->route, "loop, loopN (N traversals), reverse, both, stopgo, stops, or the world's own")
      ->capture_default_str();
  cmd->add_option("--out", options->out, "Output folder (frames/, labels.csv, loop_closure.png, map.png)");
  cmd->add_option("--fps", options->fps, "Frames per simulated second")->capture_default_str()->check(CLI::Range(0.1, 1000.0));
  cmd->add_option("--size", options->size, "Image size WxH")->capture_default_str();
  cmd->add_option("--seed", options->seed, "Seed of decoration and variations")->capture_default_str();
  cmd->add_option("--speed", options->speed, "Robot speed, m/s")->capture_default_str()->check(CLI::Range(0.02, 5.0));
  cmd->add_option("--fov", options->fov, "Horizontal field of view, degrees")->capture_default_str()->check(CLI::Range(20.0, 150.0));
  cmd->add_option("--light", options->light, "day | night | warm | cool")->capture_default_str()
      ->check(CLI::IsMember({"day", "night", "warm", "cool"}));
  cmd->add_option("--noise", options->noise, "Gaussian sensor noise sigma, grey levels")->capture_default_str()
      ->check(CLI::Range(0.0, 50.0));
  cmd->add_option("--people", options->people, "Moving people (occluders)")->capture_default_str()->check(CLI::Range(0, 20));
  cmd->add_option("--pitch", options->pitch, "Camera pitch oscillation amplitude, degrees")->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  cmd->add_flag("--moved", options->moved, "Move the furniture between traversals");
  cmd->add_option("--progress", options->progress_every, "0: no progress line (on a terminal it shows count, rate and ETA)")
      ->capture_default_str();
  cmd->add_flag("--json", options->json, "Print a summary as one JSON object (frames, seconds, traversals, rooms)");
  cmd->callback([options] { runSim(*options); });
}

}  // namespace toposlam::cli
