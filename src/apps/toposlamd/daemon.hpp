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

}  // namespace toposlam::daemon
