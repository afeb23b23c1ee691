// `toposlam bench ...`: the benchmarks were a subcommand of this program until issue 15; they are the
// program toposlam-bench now (bench/, docs/performance.md), so the production binary carries no benchmark
// code. The old command stays, hidden from --help, to tell whoever types it where they went: one line on
// stderr and exit 2 (a usage error), whatever follows `bench`.
#include <iostream>

#include "commands.hpp"

namespace toposlam::cli {

void addBenchMovedCommand(CLI::App& app) {
  auto* bench = app.add_subcommand("bench", "The benchmarks moved to toposlam-bench");
  bench->group("");  // hidden: not in --help, the man page or the completion
  // `toposlam bench fingerprint --repeat 1` gets the same line: what follows `bench` is kept unparsed by the
  // stub itself (no fall through to toposlam's own options).
  bench->fallthrough(false);
  bench->prefix_command();
  bench->callback([] {
    std::cerr << "toposlam: error: the benchmarks moved to toposlam-bench (docs/performance.md)\n";
    throw CLI::RuntimeError(2);
  });
}

}  // namespace toposlam::cli
