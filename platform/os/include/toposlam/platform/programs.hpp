// Running a helper program the way a shell would find it (on PATH), without a shell in between: the map
// command draws its topology with Graphviz `dot`. Arguments are passed as they are (no quoting, no word
// splitting); the child shares the caller's standard streams. Linux/POSIX (posix_spawnp, waitpid).
//
// Thread-safety: any thread; each call waits for its own child only.
#pragma once

#include <string>
#include <vector>

namespace toposlam {

/// True when an executable file named `name` is in one of PATH's folders.
bool programOnPath(const std::string& name);

/// Runs `argv` (argv[0] looked up on PATH) and waits for it. Returns its exit status (0: success), or -1
/// when it could not be started or did not exit normally (killed by a signal).
int runProgram(const std::vector<std::string>& argv);

}  // namespace toposlam
