// Thread settings and CPU clocks; see the header.
#include "toposlam/platform/thread_os.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <string>

namespace toposlam {

namespace {

double clockSeconds(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

}  // namespace

int setCurrentThreadName(const std::string& name) {
  return pthread_setname_np(pthread_self(), name.substr(0, 15).c_str());
}

std::function<void(int worker)> namedWorkers(const std::string& prefix) {
  return [prefix](int worker) { setCurrentThreadName(prefix + "-" + std::to_string(worker)); };
}

int pinCurrentThread(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(static_cast<unsigned>(cpu), &set);
  return pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
}

int setCurrentThreadFifoPriority(int priority) {
  sched_param param{};
  param.sched_priority = priority;
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
}

int setCurrentThreadNice(int nice) {
  // On Linux, setpriority(PRIO_PROCESS, tid) sets the nice value of one thread.
  return setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), nice) == 0 ? 0 : errno;
}

double threadCpuSeconds() { return clockSeconds(CLOCK_THREAD_CPUTIME_ID); }

double processCpuSeconds() { return clockSeconds(CLOCK_PROCESS_CPUTIME_ID); }

}  // namespace toposlam
