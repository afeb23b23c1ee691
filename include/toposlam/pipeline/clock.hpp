// Time is injected: the pipeline reads a Clock, never std::chrono directly, so tests drive time by hand
// (ManualClock) and production uses the monotonic clock (SteadyClock).
//
// Thread-safety: now() may be called from any thread; ManualClock's setters too.
#pragma once

#include <atomic>

namespace toposlam {

class Clock {
 public:
  virtual ~Clock() = default;
  /// Monotonic time in seconds from an arbitrary origin.
  virtual double now() const = 0;
};

/// std::chrono::steady_clock in seconds (CLOCK_MONOTONIC on Linux, the same clock V4L2 stamps use).
class SteadyClock final : public Clock {
 public:
  double now() const override;
};

/// A clock that only moves when told to.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(double start_s = 0.0) : now_s_(start_s) {}
  double now() const override { return now_s_.load(); }
  void set(double t_s) { now_s_.store(t_s); }
  void advance(double dt_s) {
    double t = now_s_.load();
    while (!now_s_.compare_exchange_weak(t, t + dt_s)) {
    }
  }

 private:
  std::atomic<double> now_s_;
};

}  // namespace toposlam
