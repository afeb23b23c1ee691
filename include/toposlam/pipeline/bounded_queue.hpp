// A fixed-capacity queue between two pipeline threads. When the consumer falls behind, push() drops the
// OLDEST item (real time: the newest frame matters most) and counts it; pushWait() instead blocks the
// producer until there is room (lossless replay). close() marks the end of the stream: producers are
// refused, consumers drain what is left and then get "closed". Storage is a ring allocated once at
// construction, so pushing and popping never allocate.
//
// Items that must never be dropped (records carrying a place) are named by an optional `must_keep`
// predicate: push() then drops the oldest item that may be dropped, or the new item if only it may be;
// when the queue is full of must-keep items and the new one must be kept too, push() waits for room
// (counted in `kept_waits`).
//
// Thread-safety: every member may be called from any thread. A dropped item is destroyed outside the
// lock (destroying a Frame may hand its buffer back to the source, which takes the source's lock).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace toposlam {

/// A snapshot of a queue's counters (all counts since construction).
struct QueueCounters {
  std::int64_t pushed = 0;   ///< items accepted (including ones later dropped)
  std::int64_t dropped = 0;  ///< items discarded because the queue was full (oldest first)
  std::int64_t popped = 0;   ///< items handed to a consumer
  std::int64_t refused = 0;  ///< pushes after close()
  std::int64_t kept_waits = 0;  ///< pushes that waited because every item had to be kept
  std::size_t depth = 0;     ///< items waiting now
  std::size_t capacity = 0;
  std::size_t high_water = 0;  ///< largest depth seen
};

enum class QueueWait { Item, Timeout, Closed };

template <typename T>
class BoundedQueue {
 public:
  /// `must_keep` (optional): items push() may never drop. Called with the lock held; keep it cheap.
  explicit BoundedQueue(std::size_t capacity, std::function<bool(const T&)> must_keep = {})
      : slots_(capacity), must_keep_(std::move(must_keep)) {
    if (capacity == 0) throw std::invalid_argument("BoundedQueue: capacity must be >= 1");
  }
  BoundedQueue(const BoundedQueue&) = delete;
  BoundedQueue& operator=(const BoundedQueue&) = delete;

  /// Enqueues `item`; if the queue is full the oldest droppable item is dropped (and counted), see
  /// `must_keep` above. Returns false (and counts a refusal) if the queue is (or gets) closed.
  bool push(T item) {
    std::optional<T> evicted;  // destroyed after the lock is released
    {
      std::unique_lock lock(mutex_);
      if (closed_) {
        ++counters_.refused;
        return false;
      }
      if (size_ == slots_.size()) {
        std::size_t victim = 0;  // position from the head of the oldest droppable item
        while (victim < size_ && mustKeep(*slots_[(head_ + victim) % slots_.size()])) ++victim;
        if (victim < size_) {
          evicted = removeLocked(victim);
          ++counters_.dropped;
        } else if (!mustKeep(item)) {
          ++counters_.pushed;  // accepted and dropped at once: the newest is the only droppable one
          ++counters_.dropped;
          evicted = std::move(item);
          return true;
        } else {
          ++counters_.kept_waits;
          not_full_.wait(lock, [&] { return closed_ || size_ < slots_.size(); });
          if (closed_) {
            ++counters_.refused;
            return false;
          }
        }
      }
      emplaceLocked(std::move(item));
    }
    not_empty_.notify_one();
    return true;
  }

  /// Enqueues `item`, waiting for room instead of dropping. Returns false if the queue is (or gets)
  /// closed before there was room.
  bool pushWait(T item) {
    {
      std::unique_lock lock(mutex_);
      not_full_.wait(lock, [&] { return closed_ || size_ < slots_.size(); });
      if (closed_) {
        ++counters_.refused;
        return false;
      }
      emplaceLocked(std::move(item));
    }
    not_empty_.notify_one();
    return true;
  }

  /// Blocks until an item is available (returns it) or the queue is closed and empty (nullopt).
  std::optional<T> pop() {
    std::unique_lock lock(mutex_);
    not_empty_.wait(lock, [&] { return closed_ || size_ > 0; });
    return takeLocked(lock);
  }

  /// Like pop() but gives up after `timeout` (for threads that also have periodic work).
  template <typename Rep, typename Period>
  QueueWait popFor(T& out, std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock lock(mutex_);
    if (!not_empty_.wait_for(lock, timeout, [&] { return closed_ || size_ > 0; })) return QueueWait::Timeout;
    std::optional<T> item = takeLocked(lock);
    if (!item) return QueueWait::Closed;
    out = std::move(*item);
    return QueueWait::Item;
  }

  /// Non-blocking: an item if one is waiting.
  std::optional<T> tryPop() {
    std::unique_lock lock(mutex_);
    if (size_ == 0) return std::nullopt;
    return takeLocked(lock);
  }

  /// End of stream: wakes every waiting producer and consumer. Items already queued can still be popped.
  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    not_empty_.notify_all();
    not_full_.notify_all();
  }

  bool closed() const {
    std::lock_guard lock(mutex_);
    return closed_;
  }

  QueueCounters counters() const {
    std::lock_guard lock(mutex_);
    QueueCounters c = counters_;
    c.depth = size_;
    c.capacity = slots_.size();
    return c;
  }

  std::size_t capacity() const { return slots_.size(); }

 private:
  void emplaceLocked(T&& item) {
    slots_[(head_ + size_) % slots_.size()].emplace(std::move(item));
    ++size_;
    ++counters_.pushed;
    if (size_ > counters_.high_water) counters_.high_water = size_;
  }

  bool mustKeep(const T& item) const { return must_keep_ && must_keep_(item); }

  /// Removes the item `position` places after the head, closing the gap (order is kept).
  std::optional<T> removeLocked(std::size_t position) {
    const std::size_t n = slots_.size();
    std::optional<T> removed = std::move(slots_[(head_ + position) % n]);
    for (std::size_t i = position; i > 0; --i)  // shift the older items one place towards the tail
      slots_[(head_ + i) % n] = std::move(slots_[(head_ + i - 1) % n]);
    slots_[head_].reset();
    head_ = (head_ + 1) % n;
    --size_;
    return removed;
  }

  std::optional<T> takeLocked(std::unique_lock<std::mutex>& lock) {
    if (size_ == 0) return std::nullopt;  // closed and drained
    std::optional<T> item = std::move(slots_[head_]);
    slots_[head_].reset();
    head_ = (head_ + 1) % slots_.size();
    --size_;
    ++counters_.popped;
    lock.unlock();
    not_full_.notify_one();
    return item;
  }

  mutable std::mutex mutex_;
  std::condition_variable not_empty_;
  std::condition_variable not_full_;
  std::vector<std::optional<T>> slots_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  bool closed_ = false;
  QueueCounters counters_;
  std::function<bool(const T&)> must_keep_;
};

}  // namespace toposlam
