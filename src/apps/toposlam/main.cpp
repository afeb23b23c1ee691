// toposlam: the offline command-line tool (fingerprint, similarity, localize, segment, map, sim, eval,
// report, bench, listen). Thin: it parses arguments, builds the objects and runs them.
#include <exception>
#include <iostream>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"toposlam: visual topological SLAM for indoor robots with one forward-facing camera"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "toposlam 0.1.0");
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
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "toposlam: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
