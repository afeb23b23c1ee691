// The calling thread's signal mask; see the header.
#include "toposlam/platform/signal_mask.hpp"

#include <pthread.h>
#include <signal.h>

#include <cerrno>

namespace toposlam {

namespace {

int changeMask(int how, const std::vector<int>& signals) {
  sigset_t set;
  sigemptyset(&set);
  for (int s : signals)
    if (sigaddset(&set, s) != 0) return errno;
  return pthread_sigmask(how, &set, nullptr);
}

}  // namespace

int blockSignals(const std::vector<int>& signals) { return changeMask(SIG_BLOCK, signals); }

int unblockSignals(const std::vector<int>& signals) { return changeMask(SIG_UNBLOCK, signals); }

}  // namespace toposlam
