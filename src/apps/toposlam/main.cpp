// toposlam: the offline command-line tool (fingerprint, similarity, localize, segment, map, sim, eval,
// report, bench, listen, config). Thin: it parses arguments, builds the objects and runs them.
//
// Exit status, the same in every command and in toposlamd: 0 ok, 1 runtime error (a file, camera or the
// network failed), 2 usage or config error (bad option, bad value, bad config file). CLI11's own codes
// (105-109 and up) are folded into 2 here.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>

#include <spdlog/spdlog.h>

#include "commands.hpp"
#include "toposlam/config/daemon_config.hpp"
#include "toposlam/platform/logging.hpp"
#include "toposlam/platform/opencv_runtime.hpp"

namespace {

// What a command printed must have reached its reader: `toposlam fingerprint --json x > /dev/full` used to
// exit 0 with nothing written. stdout is flushed here, before exit would do it silently; a failure is
// exit 1 naming it (an error already reported keeps its own status).
int checkStandardOutput(int status) {
  errno = 0;
  std::cout.flush();
  const bool failed = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout) != 0;
  if (!failed) return status;
  const int error = errno;
  if (status == 0) {
    std::cerr << "toposlam: error: standard output: write failed"
              << (error != 0 ? std::string(": ") + std::strerror(error) : std::string()) << "\n";
  }
  return status == 0 ? 1 : status;
}

int run(int argc, char** argv) {
  CLI::App app{"toposlam: visual topological SLAM for indoor robots with one forward-facing camera"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "toposlam " TOPOSLAM_VERSION);  // project(VERSION), the package version
  // Log lines of the stages a command runs (sources, pipeline) go to stderr; stdout is the command's output.
  // --log-level is accepted before or after the command (fallthrough) and applies as soon as it is parsed,
  // before any command runs.
  toposlam::configureLogging("toposlam", spdlog::level::info);
  app.fallthrough();
  app.add_option("--log-level", "log level: trace, debug, info, warn or error (default info)")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}))
      ->each([](const std::string& level) { spdlog::default_logger()->set_level(*toposlam::parseLogLevel(level)); });
  toposlam::cli::addFingerprintCommand(app);
  toposlam::cli::addBenchCommand(app);
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
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // a command's own status, already explained on stderr
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints the help, the version or the usage error
    return code == 0 ? 0 : 2;
  } catch (const toposlam::ConfigError& e) {
    std::cerr << "toposlam: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "toposlam: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  toposlam::keepOpenCvOffOpenCl();
  return checkStandardOutput(run(argc, argv));
}
