// toposlam-bench: the benchmarks of toposlam, a program of their own (they were `toposlam bench` until
// issue 15, inside the production binary). `toposlam-bench NAME [options] [--json]`: fingerprint,
// topology, segmentation, sim, similarity, pipeline, map-size, startup (docs/performance.md).
// Options, output and JSON are those of `toposlam bench`; exit status and --log-level those of toposlam.
#include <spdlog/spdlog.h>

#include "benchmarks.hpp"
#include "cli_main.hpp"
#include "toposlam/platform/logging.hpp"
#include "toposlam/platform/opencv_runtime.hpp"

namespace {

int run(int argc, char** argv) {
  CLI::App app{"toposlam-bench: benchmarks of toposlam; print timings, fail nothing"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "toposlam-bench " TOPOSLAM_VERSION);
  // Log lines of the stages a benchmark runs (sources, pipeline) go to stderr; stdout is the results.
  toposlam::configureLogging("toposlam-bench", spdlog::level::info);
  toposlam::cli::addLogLevelOption(app);
  toposlam::cli::addBenchFingerprint(app);
  toposlam::cli::addBenchTopology(app);
  toposlam::cli::addBenchSegmentation(app);
  toposlam::cli::addBenchSim(app);
  toposlam::cli::addBenchMatching(app);
  toposlam::cli::addBenchPipeline(app);
  toposlam::cli::addBenchMapSize(app);
  toposlam::cli::addBenchRevisits(app);
  toposlam::cli::addBenchStartup(app);
  return toposlam::cli::runCommandLine(app, argc, argv, "toposlam-bench");
}

}  // namespace

int main(int argc, char** argv) {
  toposlam::keepOpenCvOffOpenCl();
  return run(argc, argv);
}
