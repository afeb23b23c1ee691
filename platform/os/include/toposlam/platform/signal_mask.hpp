// The calling thread's signal mask, and taking signals: the programs block their stop signals so that no
// thread but the one that waits for them (toposlamd's main thread with waitForSignal, `toposlam listen`'s
// with catchSignals' handler) ever takes one. A thread starts with its creator's mask, so blocking before any thread exists blocks
// the signals for every thread of the process. Linux/POSIX (pthread_sigmask, sigtimedwait, sigaction).
//
// Each function returns 0, or the error number the system gave (an invalid signal number: EINVAL).
// Thread-safety: any thread; each call changes its caller's mask only.
#pragma once

#include <vector>

namespace toposlam {

/// Every signal whose default action ends the process, that another process can send, and that a thread
/// waiting for it (waitForSignal) can take safely: SIGHUP, SIGINT, SIGQUIT, SIGTERM, SIGUSR1, SIGUSR2,
/// SIGALRM, SIGXCPU, SIGVTALRM, SIGPROF, SIGIO, SIGPWR, SIGSYS, SIGSTKFLT and SIGRTMIN..SIGRTMAX (those the C
/// library does not keep for itself). Not in it: SIGKILL and SIGSTOP (they cannot be caught); SIGSEGV,
/// SIGBUS, SIGFPE, SIGILL, SIGTRAP and SIGABRT (a fault of the thread that raised it, or a request for a
/// core dump: nothing in the process is trusted to be saved); SIGPIPE and SIGXFSZ (raised in the thread
/// whose write failed: ignore them with ignoreSignals, and the write fails with EPIPE or EFBIG instead).
/// SIGSYS sent by another process is taken like SIGTERM; one the kernel raises for a forbidden system call
/// (seccomp) is delivered despite the mask and ends the process as before.
std::vector<int> catchableTerminatingSignals();

/// Sets `signals` to be ignored by the whole process (SIG_IGN): SIGPIPE, SIGXFSZ. Returns 0 or the error
/// number.
int ignoreSignals(const std::vector<int>& signals);

/// Adds `signals` (SIGINT, SIGTERM, ...) to the calling thread's blocked set: they stay pending until
/// unblocked or taken with sigwait/sigtimedwait.
int blockSignals(const std::vector<int>& signals);
/// Removes `signals` from the calling thread's blocked set (a pending one is delivered at once).
int unblockSignals(const std::vector<int>& signals);

/// Takes one of `signals` (blocked, pending for this thread or the process) within `seconds` (sigtimedwait):
/// returns its number, or 0 when none came in time (or the wait was interrupted by another signal).
int waitForSignal(const std::vector<int>& signals, double seconds);

/// Installs `handler` for `signals` without SA_RESTART, so a blocking call (select, read) that one of them
/// interrupts returns EINTR and its caller can look at what the handler set; then unblocks them in the
/// calling thread. Returns 0 or the error number.
int catchSignals(const std::vector<int>& signals, void (*handler)(int));

}  // namespace toposlam
