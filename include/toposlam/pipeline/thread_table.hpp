// The pipeline's threads are a fixed table: each is created once at start with a name (visible in top,
// ps -L and gdb), optionally pinned to a CPU and given a real-time (SCHED_FIFO) priority or a nice
// value, and joined at stop. Failing to apply a priority or pinning (no CAP_SYS_NICE, CPU absent) is
// logged and recorded, never fatal: the thread runs with default scheduling.
//
// Thread-safety: start() and joinAll() from the owning thread only; warnings() after start.
#pragma once

#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace toposlam {

enum class SchedulingPolicy { Other, Fifo };

struct ThreadSettings {
  std::string name;             ///< at most 15 characters (Linux limit)
  int cpu = -1;                 ///< CPU index to pin to; -1 = no pinning
  SchedulingPolicy policy = SchedulingPolicy::Other;
  int priority = 0;             ///< SCHED_FIFO priority 1..99 (only with policy Fifo)
  int nice = 0;                 ///< -20..19 (only with policy Other; 0 = leave as is)
  /// "" or "<key>: <problem, allowed range>" (keys: name, cpu, policy, priority, nice).
  std::string validate() const;
};

const char* toString(SchedulingPolicy policy);

/// Applies name, pinning and priority to the calling thread. Returns the problems met (empty if none).
std::vector<std::string> applyThreadSettings(const ThreadSettings& settings);

class ThreadTable {
 public:
  ThreadTable() = default;
  ~ThreadTable();  ///< joins every thread still running
  ThreadTable(const ThreadTable&) = delete;
  ThreadTable& operator=(const ThreadTable&) = delete;

  /// Creates one thread that applies `settings` to itself and then runs `body`. An exception escaping
  /// `body` is logged and recorded (the thread ends; the others keep running).
  void start(const ThreadSettings& settings, std::function<void()> body);
  /// Joins all threads (idempotent).
  void joinAll();
  std::size_t size() const { return threads_.size(); }
  /// Priority/pinning problems and escaped exceptions, one line each.
  std::vector<std::string> warnings() const;

 private:
  std::vector<std::thread> threads_;
  mutable std::mutex mutex_;
  std::vector<std::string> warnings_;
};

}  // namespace toposlam
