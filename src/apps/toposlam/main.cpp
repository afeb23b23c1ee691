// toposlam: the offline command-line tool (fingerprint, similarity, localize, segment, map, sim, eval,
// report, bench, listen). Thin: it parses arguments, builds the objects and runs them.
//
// Exit status, the same in every command and in toposlamd: 0 ok, 1 runtime error (a file, camera or the
// network failed), 2 usage or config error (bad option, bad value, bad config file). CLI11's own codes
// (105-109 and up) are folded into 2 here.
#include <exception>
#include <iostream>

#include <spdlog/spdlog.h>

#include "commands.hpp"
#include "toposlam/config/daemon_config.hpp"
#include "toposlam/platform/logging.hpp"

int main(int argc, char** argv) {
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
