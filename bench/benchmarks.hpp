// The benchmarks of toposlam-bench, each a subcommand in its own bench_<name>.cpp, registered by main.cpp.
// A benchmark prints numbers (median and p99 ms, rates; --json for one JSON object) and fails nothing: a
// slow machine is not an error. Errors are thrown as in toposlam's commands (src/apps/common/cli_main.hpp).
#pragma once

#include <CLI/CLI.hpp>

namespace toposlam::cli {

void addBenchFingerprint(CLI::App& bench);   // fingerprint
void addBenchTopology(CLI::App& bench);      // topology
void addBenchSegmentation(CLI::App& bench);  // segmentation
void addBenchSim(CLI::App& bench);           // sim
void addBenchMatching(CLI::App& bench);      // similarity
void addBenchPipeline(CLI::App& bench);      // pipeline
void addBenchMapSize(CLI::App& bench);       // map-size
void addBenchRevisits(CLI::App& bench);      // revisits: the per-frame answer's cost per keyframe
void addBenchStartup(CLI::App& bench);       // startup: toposlam's own start-up, as child processes

}  // namespace toposlam::cli
