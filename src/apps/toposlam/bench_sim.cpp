// `toposlam bench sim`: frames per second of the simulated world's renderer on one core, per frame
// median and p99 over a whole route (prints numbers, fails nothing).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench_stats.hpp"
#include "commands.hpp"
#include "toposlam/sim/simulator.hpp"

namespace toposlam::cli {

namespace {

struct BenchSimOptions {
  std::vector<std::string> worlds = {"office", "home"};
  std::string route = "loop";
  std::vector<int> widths = {320, 640};
  int people = 0;
};

void runBenchSim(const BenchSimOptions& options) {
  for (const std::string& world : options.worlds) {
    for (const int width : options.widths) {
      sim::SimConfig config;
      config.world = world;
      config.route = options.route;
      config.fps = 5;
      config.camera.width = width;
      config.camera.height = width * 3 / 4;
      config.people = options.people;
      const sim::Simulator simulator(config);
      std::vector<double> ms;
      Stopwatch total;
      for (std::int64_t i = 0; i < simulator.frameCount(); ++i) {
        Stopwatch one;
        const sim::SimFrame frame = simulator.render(i);
        ms.push_back(one.elapsedMs());
      }
      const double seconds = total.elapsedMs() / 1000.0;
      const TimingSummary s = summarize(ms);
      std::printf("sim %-7s %4dx%-4d route %s: %5zu frames, median %.3f ms, p99 %.3f ms, max %.3f ms, %.0f frames/s\n",
                  world.c_str(), config.camera.width, config.camera.height, options.route.c_str(), s.samples,
                  s.median_ms, s.p99_ms, s.max_ms, static_cast<double>(s.samples) / seconds);
    }
  }
}

}  // namespace

void addBenchSim(CLI::App& bench) {
  auto options = std::make_shared<BenchSimOptions>();
  auto* cmd = bench.add_subcommand("sim", "frames/s of the simulated world renderer (one core)");
  cmd->add_option("--worlds", options->worlds, "Worlds to render")->capture_default_str();
  cmd->add_option("--route", options->route, "Route")->capture_default_str();
  cmd->add_option("--widths", options->widths, "Image widths (height = 3/4 width)")->capture_default_str();
  cmd->add_option("--people", options->people, "Moving people")->capture_default_str();
  cmd->callback([options] { runBenchSim(*options); });
}

}  // namespace toposlam::cli
