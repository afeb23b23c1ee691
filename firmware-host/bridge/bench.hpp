// toposlam-bridge --bench (see bench.cpp).
#pragma once

namespace toposlam::bridge {
/// Runs each protocol for about `seconds`; prints MB/s. Returns the exit code (0).
int runBenchmark(double seconds);
}  // namespace toposlam::bridge
