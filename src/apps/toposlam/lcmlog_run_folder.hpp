// A run folder (docs/run-folder.md) from toposlamd's recorded LCM log, so `toposlam report` and `toposlam
// eval` read a robot's run: frames.csv from the place estimates, places.csv from the place events,
// topology.json from the last topology, frames/NNNNNN.jpg from the place events' thumbnails. Used by
// `toposlam listen --from lcmlog:FILE --run-folder DIR` and `toposlam report lcmlog:FILE`.
#pragma once

#include <filesystem>
#include <string>

#include "toposlam/platform/lcm_log_run.hpp"

namespace toposlam::cli {

/// Writes `run` into `dir` (created). Frames whose estimate the log lacks (the publisher dropped it) get
/// the time interpolated between their neighbours and no lambda2. Throws std::runtime_error when the log
/// holds no place estimate, OutputFileError naming a file that cannot be written.
void writeRunFolderFromLog(const LoggedRun& run, const std::string& log_path, const std::filesystem::path& dir);

}  // namespace toposlam::cli
