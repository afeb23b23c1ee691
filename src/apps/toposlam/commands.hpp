// Each `toposlam` subcommand lives in its own command_<name>.cpp and registers itself here.
// A command's callback throws std::exception with a message a person can act on; main() prints it.
#pragma once

#include <CLI/CLI.hpp>

namespace toposlam::cli {

void addFingerprintCommand(CLI::App& app);
void addBenchCommand(CLI::App& app);
void addMapCommand(CLI::App& app);
void addSegmentCommand(CLI::App& app);
void addCaptureCommand(CLI::App& app);
void addSimCommand(CLI::App& app);
void addEvalCommand(CLI::App& app);
void addReportCommand(CLI::App& app);
void addListenCommand(CLI::App& app);
void addConfigCommand(CLI::App& app);
void addSimilarityCommand(CLI::App& app);
void addLocalizeCommand(CLI::App& app);
void addRecognitionCommand(CLI::App& app);

// Sub-benchmarks of `toposlam bench`, each in its module's bench_<module>.cpp (called from command_bench.cpp).
void addBenchFingerprint(CLI::App& bench);
void addBenchTopology(CLI::App& bench);
void addBenchSegmentation(CLI::App& bench);
void addBenchSim(CLI::App& bench);
void addBenchMatching(CLI::App& bench);
void addBenchPipeline(CLI::App& bench);
void addBenchMapSize(CLI::App& bench);

}  // namespace toposlam::cli
