// The measurement options `toposlam eval` and `toposlam report` share (--tolerance, --min-gap,
// --traversals, --thresholds), registered by one function so both commands accept and check them alike.
// Defined in command_eval.cpp.
#pragma once

#include <CLI/CLI.hpp>

#include "toposlam/eval/evaluation.hpp"

namespace toposlam::cli {

/// Adds the options to `command`, writing into `options` (which must outlive the parse).
void addEvalMeasureOptions(CLI::App& command, eval::EvalOptions& options);

}  // namespace toposlam::cli
