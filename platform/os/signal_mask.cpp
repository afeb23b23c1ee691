// The calling thread's signal mask; see the header.
#include "toposlam/platform/signal_mask.hpp"

#include <pthread.h>
#include <signal.h>

#include <cerrno>
#include <cmath>
#include <ctime>

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

int waitForSignal(const std::vector<int>& signals, double seconds) {
  sigset_t set;
  sigemptyset(&set);
  for (int s : signals) sigaddset(&set, s);
  const double wait = seconds > 0.0 ? seconds : 0.0;
  timespec timeout{};
  timeout.tv_sec = static_cast<time_t>(wait);
  timeout.tv_nsec = static_cast<long>((wait - std::floor(wait)) * 1e9);
  const int signal = sigtimedwait(&set, nullptr, &timeout);
  return signal > 0 ? signal : 0;
}

std::vector<int> catchableTerminatingSignals() {
  std::vector<int> signals = {SIGHUP, SIGINT, SIGQUIT, SIGTERM, SIGUSR1, SIGUSR2, SIGALRM, SIGXCPU,
                              SIGVTALRM, SIGPROF, SIGIO, SIGPWR, SIGSYS, SIGSTKFLT};
  for (int s = SIGRTMIN; s <= SIGRTMAX; ++s) signals.push_back(s);
  return signals;
}

int ignoreSignals(const std::vector<int>& signals) {
  struct sigaction action {};
  action.sa_handler = SIG_IGN;
  sigemptyset(&action.sa_mask);
  for (int s : signals)
    if (sigaction(s, &action, nullptr) != 0) return errno;
  return 0;
}

int catchSignals(const std::vector<int>& signals, void (*handler)(int)) {
  struct sigaction action {};
  action.sa_handler = handler;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART
  for (int s : signals)
    if (sigaction(s, &action, nullptr) != 0) return errno;
  return unblockSignals(signals);
}

}  // namespace toposlam
