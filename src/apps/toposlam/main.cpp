// toposlam: the offline command-line tool (fingerprint, similarity, localize, segment, map, sim, eval,
// report, listen, config, view). Thin: it parses arguments, builds the objects and runs them. The benchmarks are
// a program of their own, toposlam-bench (bench/); `toposlam bench` only says so (command_bench.cpp).
//
// Exit status (src/apps/common/cli_main.hpp): 0 ok, 1 runtime error, 2 usage or config error.
#include <csignal>

#include <spdlog/spdlog.h>

#include "cli_main.hpp"
#include "commands.hpp"
#include "toposlam/platform/logging.hpp"
#include "toposlam/platform/opencv_runtime.hpp"
#include "toposlam/platform/process_resources.hpp"
#include "toposlam/platform/signal_mask.hpp"

namespace {

int run(int argc, char** argv) {
  CLI::App app{"toposlam: visual topological SLAM for indoor robots with one forward-facing camera"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "toposlam " TOPOSLAM_VERSION);  // project(VERSION), the package version
  // Log lines of the stages a command runs (sources, pipeline) go to stderr; stdout is the command's output.
  toposlam::configureLogging("toposlam", spdlog::level::info);
  toposlam::cli::addLogLevelOption(app);
  toposlam::cli::addFingerprintCommand(app);
  toposlam::cli::addBenchMovedCommand(app);
  toposlam::cli::addMapCommand(app);
  toposlam::cli::addSegmentCommand(app);
  toposlam::cli::addCaptureCommand(app);
  toposlam::cli::addSimCommand(app);
  toposlam::cli::addEvalCommand(app);
  toposlam::cli::addReportCommand(app);
  toposlam::cli::addListenCommand(app);
  toposlam::cli::addConfigCommand(app);
  toposlam::cli::addSimilarityCommand(app);
  toposlam::cli::addLocalizeCommand(app);
  toposlam::cli::addRecognitionCommand(app);
  toposlam::cli::addMapInfoCommand(app);
  toposlam::cli::addExportCommand(app);
  toposlam::cli::addViewCommand(app);
  return toposlam::cli::runCommandLine(app, argc, argv, "toposlam");
}

}  // namespace

int main(int argc, char** argv) {
  toposlam::keepOpenCvOffOpenCl();
  // A file written beyond the file-size limit (ulimit -f) is a failed write (EFBIG) that the command reports,
  // keeping the file it would have replaced, not death by SIGXFSZ halfway.
  toposlam::ignoreSignals({SIGXFSZ});
  // Frames are decoded, converted and fingerprinted in buffers of a few hundred KB that glibc would map
  // and unmap afresh every frame: kept on the heap instead, `toposlam map` on the bundled samples takes
  // about a third less CPU (page faults 10,600 -> 4,000), at the same peak memory (docs/performance.md).
  toposlam::reuseFreedMemory(std::size_t{32} << 20, std::size_t{64} << 20);
  return run(argc, argv);
}
