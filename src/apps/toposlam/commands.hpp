// Each `toposlam` subcommand lives in its own command_<name>.cpp and registers itself here.
// A command's callback throws std::exception with a message a person can act on; main() prints it.
#pragma once

#include <CLI/CLI.hpp>

namespace toposlam::cli {

void addFingerprintCommand(CLI::App& app);
/// `toposlam bench ...`, hidden: one line saying the benchmarks moved to toposlam-bench, exit 2.
void addBenchMovedCommand(CLI::App& app);
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
/// `toposlam map-info MAP` and `toposlam export MAP --out DIR` (command_map_info.cpp).
void addMapInfoCommand(CLI::App& app);
void addExportCommand(CLI::App& app);
/// `toposlam view`: the live web view of toposlamd's LCM messages (command_view.cpp, view/live_view.py).
void addViewCommand(CLI::App& app);

}  // namespace toposlam::cli
