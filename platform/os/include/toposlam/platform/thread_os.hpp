// The calling thread's OS settings (name, CPU pinning, SCHED_FIFO priority, nice value) and the CPU
// clocks of the thread and of the process, for the pipeline's thread table and its CPU accounting.
// Linux only (pthread_setname_np, pthread_setaffinity_np, pthread_setschedparam, setpriority on a thread
// id, CLOCK_THREAD_CPUTIME_ID / CLOCK_PROCESS_CPUTIME_ID).
//
// Each setter acts on the calling thread and returns 0, or the error number the system gave (for
// std::strerror); the caller decides what a failure means (the thread table logs it and runs on).
// Thread-safety: every function may be called from any thread; it reads or changes only its caller.
#pragma once

#include <functional>
#include <string>

namespace toposlam {

/// Names the calling thread (visible in top, ps -L, gdb); at most 15 characters are kept.
int setCurrentThreadName(const std::string& name);
/// A WorkerPool's on_thread_start that names worker i "<prefix>-<i>" (cut to 15 characters).
std::function<void(int worker)> namedWorkers(const std::string& prefix);
/// Pins the calling thread to CPU `cpu` (0 .. 1023).
int pinCurrentThread(int cpu);
/// Gives the calling thread real-time scheduling, SCHED_FIFO with `priority` (1 .. 99).
int setCurrentThreadFifoPriority(int priority);
/// Sets the nice value (-20 .. 19) of the calling thread alone.
int setCurrentThreadNice(int nice);

/// CPU time the calling thread has used, seconds.
double threadCpuSeconds();
/// CPU time the whole process has used (all threads), seconds.
double processCpuSeconds();

}  // namespace toposlam
