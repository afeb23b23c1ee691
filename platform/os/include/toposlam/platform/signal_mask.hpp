// The calling thread's signal mask: the programs block their stop signals so that no thread but the one
// that waits for them (toposlamd's main thread with sigtimedwait, `toposlam listen`'s with a handler)
// ever takes one. A thread starts with its creator's mask, so blocking before any thread exists blocks
// the signals for every thread of the process. Linux/POSIX (pthread_sigmask).
//
// Each function returns 0, or the error number the system gave (an invalid signal number: EINVAL).
// Thread-safety: any thread; each call changes its caller's mask only.
#pragma once

#include <vector>

namespace toposlam {

/// Adds `signals` (SIGINT, SIGTERM, ...) to the calling thread's blocked set: they stay pending until
/// unblocked or taken with sigwait/sigtimedwait.
int blockSignals(const std::vector<int>& signals);
/// Removes `signals` from the calling thread's blocked set (a pending one is delivered at once).
int unblockSignals(const std::vector<int>& signals);

}  // namespace toposlam
