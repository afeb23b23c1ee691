// WorkerPool: a fixed set of threads that run batches of indexed tasks; see the header.
#include "toposlam/core/worker_pool.hpp"

#include <stdexcept>

namespace toposlam {

WorkerPool::WorkerPool(int total_workers, std::function<void(int worker)> on_thread_start) {
  if (total_workers < 1) throw std::invalid_argument("WorkerPool: total_workers must be >= 1");
  threads_.reserve(static_cast<std::size_t>(total_workers - 1));
  for (int i = 1; i < total_workers; ++i) {
    threads_.emplace_back([this, i, on_thread_start] {
      if (on_thread_start) on_thread_start(i);
      workerLoop();
    });
  }
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  work_ready_.notify_all();
  for (auto& t : threads_) t.join();
}

void WorkerPool::run(std::size_t task_count, const std::function<void(std::size_t)>& task) {
  if (task_count == 0) return;
  {
    std::lock_guard lock(mutex_);
    task_ = &task;
    task_count_ = task_count;
    next_task_ = 0;
    finished_tasks_ = 0;
    first_error_ = nullptr;
    ++generation_;
  }
  work_ready_.notify_all();
  drain();
  std::unique_lock lock(mutex_);
  work_done_.wait(lock, [&] { return finished_tasks_ == task_count_; });
  task_ = nullptr;
  if (first_error_) std::rethrow_exception(first_error_);
}

// Takes tasks of the current batch until none is left.
void WorkerPool::drain() {
  std::unique_lock lock(mutex_);
  while (task_ != nullptr && next_task_ < task_count_) {
    const std::size_t index = next_task_++;
    const auto* task = task_;
    lock.unlock();
    std::exception_ptr error;
    try {
      (*task)(index);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    if (error && !first_error_) first_error_ = error;
    if (++finished_tasks_ == task_count_) work_done_.notify_all();
  }
}

void WorkerPool::workerLoop() {
  std::size_t seen_generation = 0;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      work_ready_.wait(lock, [&] { return stopping_ || generation_ != seen_generation; });
      if (stopping_) return;
      seen_generation = generation_;
    }
    drain();
  }
}

}  // namespace toposlam
