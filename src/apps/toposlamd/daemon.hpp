// toposlamd's body: builds the stages from the config, runs the pipeline, talks to systemd, stops
// cleanly on SIGTERM/SIGINT (finishes the filter step in progress, saves the map, exit code 0).
#pragma once

#include <optional>
#include <string>

#include "toposlam/config/daemon_config.hpp"

namespace toposlam::daemon {

/// Resolves a relative map path against $STATE_DIRECTORY (systemd's StateDirectory=), else the
/// current directory; an absolute path is kept.
std::string resolveMapPath(const std::string& path);

/// Runs until the source ends or a stop signal arrives. Returns the process exit code.
int runDaemon(const DaemonConfig& config);

struct BenchOptions {
  std::string source;          ///< base source URI (a sim: URI; size/fps are added per run)
  int frames = 600;            ///< frames per run
  std::string lcm_url;         ///< where to publish (the latency includes the LCM publish)
};

/// `toposlamd --bench`: sustained fps and capture-to-publish latency at 320x240 and 640x480.
int runBench(const DaemonConfig& config, const BenchOptions& options);

}  // namespace toposlam::daemon
