// A fixed pool of worker threads, created once and joined on destruction. Used to run the per-subregion
// work of one frame in parallel (no thread per frame). run() blocks until every task of the batch is done;
// the calling thread works too, so a pool of size 1 has no extra thread at all. No OS calls of its own:
// a caller that wants the threads named (or pinned) passes `on_thread_start`, which each worker runs first
// (the programs pass platform/os's setCurrentThreadName, see namedWorkers() in thread_os.hpp).
//
// Thread-safety: run() may be called from one thread at a time.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace toposlam {

class WorkerPool {
 public:
  /// total_workers counts the caller: 1 means "run inline", N means N-1 extra threads, numbered 1 .. N-1
  /// for `on_thread_start` (run on each new thread before any task).
  explicit WorkerPool(int total_workers, std::function<void(int worker)> on_thread_start = {});
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int size() const { return static_cast<int>(threads_.size()) + 1; }

  /// Runs task(i) for i in [0, task_count), spread over the workers; returns when all are done.
  /// Exceptions from tasks are rethrown (the first one) after the batch finishes.
  void run(std::size_t task_count, const std::function<void(std::size_t)>& task);

 private:
  void workerLoop();
  void drain();

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable work_ready_;
  std::condition_variable work_done_;
  const std::function<void(std::size_t)>* task_ = nullptr;
  std::size_t task_count_ = 0;
  std::size_t next_task_ = 0;
  std::size_t finished_tasks_ = 0;
  std::size_t generation_ = 0;
  std::exception_ptr first_error_;
  bool stopping_ = false;
};

}  // namespace toposlam
