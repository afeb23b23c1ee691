// The signal mask helper (platform/os): a blocked signal waits, pending, until it is taken or unblocked;
// the threads started afterwards inherit the mask; a bad signal number is refused with EINVAL.
#include <catch2/catch.hpp>

#include <pthread.h>
#include <signal.h>

#include <cerrno>
#include <thread>

#include "toposlam/platform/signal_mask.hpp"

using namespace toposlam;

namespace {

bool blockedHere(int signal) {
  sigset_t current;
  sigemptyset(&current);
  pthread_sigmask(SIG_BLOCK, nullptr, &current);
  return sigismember(&current, signal) == 1;
}

}  // namespace

SCENARIO(
    "GIVEN SIGUSR2 blocked WHEN it is raised THEN it waits pending, and threads started afterwards block it "
    "too") {
  REQUIRE(blockSignals({SIGUSR2}) == 0);
  CHECK(blockedHere(SIGUSR2));
  bool blocked_in_thread = false;
  std::thread([&] { blocked_in_thread = blockedHere(SIGUSR2); }).join();
  CHECK(blocked_in_thread);

  REQUIRE(raise(SIGUSR2) == 0);  // without the block, the default action would end the test program
  sigset_t pending;
  sigemptyset(&pending);
  REQUIRE(sigpending(&pending) == 0);
  CHECK(sigismember(&pending, SIGUSR2) == 1);
  sigset_t wanted;
  sigemptyset(&wanted);
  sigaddset(&wanted, SIGUSR2);
  const timespec no_wait{0, 0};
  CHECK(sigtimedwait(&wanted, nullptr, &no_wait) == SIGUSR2);  // taken, no longer pending

  CHECK(unblockSignals({SIGUSR2}) == 0);
  CHECK_FALSE(blockedHere(SIGUSR2));
  CHECK(blockSignals({SIGUSR2, 100000}) == EINVAL);
  CHECK_FALSE(blockedHere(SIGUSR2));
}
