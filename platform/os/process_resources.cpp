// Process CPUs and resident memory for the benchmarks; see the header.
#include "toposlam/platform/process_resources.hpp"

#include <malloc.h>
#include <sched.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

namespace toposlam {

namespace {

/// A "Name:   1234 kB" line of /proc/self/status, in bytes; 0 when absent.
std::size_t statusKilobytes(const char* name) {
  std::ifstream status("/proc/self/status");
  std::string line;
  const std::string prefix = std::string(name) + ":";
  while (std::getline(status, line)) {
    if (line.rfind(prefix, 0) != 0) continue;
    std::istringstream fields(line.substr(prefix.size()));
    std::size_t kilobytes = 0;
    fields >> kilobytes;
    return kilobytes * 1024;
  }
  return 0;
}

}  // namespace

std::vector<int> allowedCpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  std::vector<int> cpus;
  if (sched_getaffinity(0, sizeof(set), &set) != 0) return cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  return cpus;
}

std::string restrictToCpus(const std::vector<int>& cpus) {
  cpu_set_t set;
  CPU_ZERO(&set);
  for (int cpu : cpus) {
    if (cpu < 0 || cpu >= CPU_SETSIZE) return "CPU " + std::to_string(cpu) + " is out of range";
    CPU_SET(cpu, &set);
  }
  if (sched_setaffinity(0, sizeof(set), &set) != 0) return std::string("sched_setaffinity: ") + std::strerror(errno);
  return "";
}

std::size_t residentBytes() { return statusKilobytes("VmRSS"); }

std::size_t peakResidentBytes() { return statusKilobytes("VmHWM"); }

bool resetPeakResident() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
  clear.flush();
  return static_cast<bool>(clear);
}

bool reuseFreedMemory(std::size_t heap_block_bytes, std::size_t keep_free_bytes) {
  const auto clamp = [](std::size_t v) { return static_cast<int>(std::min<std::size_t>(v, 1u << 30)); };
  // Setting either also stops glibc's own adjustment of both (its "dynamic" thresholds).
  return ::mallopt(M_MMAP_THRESHOLD, clamp(heap_block_bytes)) == 1 &&
         ::mallopt(M_TRIM_THRESHOLD, clamp(keep_free_bytes)) == 1;
}

}  // namespace toposlam
