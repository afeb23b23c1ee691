// The command line's run, the same in `toposlam` and `toposlam-bench`: --log-level, the exit statuses and
// the check that what a command printed reached stdout.
//
// Exit status, the same in every command and in toposlamd: 0 ok, 1 runtime error (a file, camera or the
// network failed), 2 usage or config error (bad option, bad value, bad config file). CLI11's own codes
// (105-109 and up) are folded into 2 here.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

namespace toposlam::cli {

/// Adds `--log-level trace|debug|info|warn|error`, accepted before or after the command (the app falls
/// through) and applied as soon as it is parsed, before any command runs. Log lines go to stderr.
void addLogLevelOption(CLI::App& app);

/// Parses `argv` into `app` (running the chosen command's callback) and returns the exit status above.
/// Errors are printed as "PROGRAM: error: what"; a CLI::RuntimeError carries a status already explained.
/// stdout is flushed before returning: a failed write is exit 1 naming it (`... --json > /dev/full`).
int runCommandLine(CLI::App& app, int argc, char** argv, const std::string& program);

}  // namespace toposlam::cli
