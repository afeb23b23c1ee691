// What the benchmarks need from the OS about this process: which CPUs it may run on (and narrowing that,
// the way `taskset` does), and its resident memory, current and peak. Linux only (sched_setaffinity,
// /proc/self/status, /proc/self/clear_refs). And how freed memory is kept for reuse (glibc's mallopt).
//
// Thread-safety: the affinity calls act on the calling thread (threads it creates afterwards inherit
// the mask); the memory calls read process-wide values and may be called from any thread.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace toposlam {

/// CPUs the calling thread may run on, ascending (empty if the kernel does not say).
std::vector<int> allowedCpus();
/// Restricts the calling thread, and every thread it creates from now on, to `cpus`. Returns "" or the
/// problem (a CPU that does not exist, no permission).
std::string restrictToCpus(const std::vector<int>& cpus);

/// Resident set size now (VmRSS), bytes; 0 when unknown.
std::size_t residentBytes();
/// Highest resident set size so far (VmHWM, or since resetPeakResident()), bytes; 0 when unknown.
std::size_t peakResidentBytes();
/// Starts a new peak from the current resident size (writes "5" to /proc/self/clear_refs). False when the
/// kernel refuses (then peakResidentBytes() keeps the whole process's peak).
bool resetPeakResident();

/// Keeps freed heap memory for reuse rather than handing it back to the kernel at once: blocks up to
/// `heap_block_bytes` come from the heap (not a fresh mapping each, which glibc otherwise makes for blocks
/// of a few hundred KB, a decoded frame's size), and up to `keep_free_bytes` free at the heap's top stay
/// mapped. A replay frees and allocates the same frame-sized buffers every frame; a fresh mapping costs a
/// page fault per 4 KB touched. Call once, before any thread starts. False when the allocator refuses.
bool reuseFreedMemory(std::size_t heap_block_bytes, std::size_t keep_free_bytes);

}  // namespace toposlam
