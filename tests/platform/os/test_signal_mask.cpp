// The signal mask helper (platform/os): a blocked signal waits, pending, until it is taken or unblocked;
// the threads started afterwards inherit the mask; a bad signal number is refused with EINVAL.
#include <catch2/catch.hpp>

#include <pthread.h>
#include <signal.h>

#include <cerrno>
#include <chrono>
#include <csignal>
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

namespace {
volatile std::sig_atomic_t g_caught = 0;
void onSignal(int signal) { g_caught = signal; }
}  // namespace

SCENARIO("GIVEN SIGUSR1 blocked WHEN waited for THEN waitForSignal takes it when it is pending and times out when not") {
  std::thread([] {
    REQUIRE(blockSignals({SIGUSR1}) == 0);  // this thread only
    const auto t0 = std::chrono::steady_clock::now();
    CHECK(waitForSignal({SIGUSR1}, 0.05) == 0);  // nothing pending: the time runs out
    CHECK(std::chrono::steady_clock::now() - t0 >= std::chrono::milliseconds(45));
    REQUIRE(pthread_kill(pthread_self(), SIGUSR1) == 0);
    CHECK(waitForSignal({SIGUSR2, SIGUSR1}, 5.0) == SIGUSR1);  // taken at once
    CHECK(waitForSignal({SIGUSR1}, 0.0) == 0);                 // and no longer pending
  }).join();
}

SCENARIO("GIVEN catchSignals on a blocked signal WHEN the signal comes THEN the handler runs and it is unblocked") {
  std::thread([] {
    REQUIRE(blockSignals({SIGUSR2}) == 0);
    g_caught = 0;
    REQUIRE(catchSignals({SIGUSR2}, onSignal) == 0);
    CHECK_FALSE(blockedHere(SIGUSR2));
    REQUIRE(pthread_kill(pthread_self(), SIGUSR2) == 0);  // delivered before pthread_kill returns
    CHECK(g_caught == SIGUSR2);
    CHECK(catchSignals({100000}, onSignal) == EINVAL);
    signal(SIGUSR2, SIG_DFL);
  }).join();
}
