// ThreadTable: named, optionally pinned and prioritised threads created once and joined at stop.
#include "toposlam/pipeline/thread_table.hpp"

#include <cstring>
#include <exception>

#include <spdlog/spdlog.h>

#include "toposlam/platform/thread_os.hpp"

namespace toposlam {

const char* toString(SchedulingPolicy policy) { return policy == SchedulingPolicy::Fifo ? "fifo" : "other"; }

std::string ThreadSettings::validate() const {
  if (name.empty() || name.size() > 15) return "name: must have 1 to 15 characters (Linux limit), got '" + name + "'";
  if (cpu < -1 || cpu > 1023) return "cpu: " + std::to_string(cpu) + " is out of range, allowed -1 (no pinning) .. 1023";
  if (policy == SchedulingPolicy::Fifo && (priority < 1 || priority > 99))
    return "priority: " + std::to_string(priority) + " is out of range for policy fifo, allowed 1 .. 99";
  if (policy == SchedulingPolicy::Other && priority != 0)
    return "priority: only used with policy fifo; must be 0 with policy other, got " + std::to_string(priority);
  if (nice < -20 || nice > 19) return "nice: " + std::to_string(nice) + " is out of range, allowed -20 .. 19";
  return "";
}

std::vector<std::string> applyThreadSettings(const ThreadSettings& settings) {
  std::vector<std::string> problems;
  const std::string name = settings.name.substr(0, 15);
  if (int rc = setCurrentThreadName(name); rc != 0)
    problems.push_back(name + ": cannot set the thread name: " + std::strerror(rc));
  if (settings.cpu >= 0) {
    if (int rc = pinCurrentThread(settings.cpu); rc != 0)
      problems.push_back(name + ": cannot pin to CPU " + std::to_string(settings.cpu) + ": " + std::strerror(rc));
  }
  if (settings.policy == SchedulingPolicy::Fifo) {
    if (int rc = setCurrentThreadFifoPriority(settings.priority); rc != 0)
      problems.push_back(name + ": cannot set SCHED_FIFO priority " + std::to_string(settings.priority) + ": " +
                         std::strerror(rc) + " (needs CAP_SYS_NICE or LimitRTPRIO); running with default scheduling");
  } else if (settings.nice != 0) {
    if (int rc = setCurrentThreadNice(settings.nice); rc != 0)
      problems.push_back(name + ": cannot set nice " + std::to_string(settings.nice) + ": " + std::strerror(rc));
  }
  return problems;
}

ThreadTable::~ThreadTable() { joinAll(); }

void ThreadTable::start(const ThreadSettings& settings, std::function<void()> body) {
  threads_.emplace_back([this, settings, body = std::move(body)] {
    for (const std::string& problem : applyThreadSettings(settings)) {
      spdlog::warn("thread {}", problem);
      std::lock_guard lock(mutex_);
      warnings_.push_back(problem);
    }
    try {
      body();
    } catch (const std::exception& e) {
      spdlog::error("thread {} ended by an exception: {}", settings.name, e.what());
      std::lock_guard lock(mutex_);
      warnings_.push_back(settings.name + ": ended by an exception: " + e.what());
    }
  });
}

void ThreadTable::joinAll() {
  for (std::thread& t : threads_)
    if (t.joinable()) t.join();
}

std::vector<std::string> ThreadTable::warnings() const {
  std::lock_guard lock(mutex_);
  return warnings_;
}

}  // namespace toposlam
