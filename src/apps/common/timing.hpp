// Wall-clock timing for the programs' own reports (toposlam-bench's benchmarks, `toposlam segment`'s ms per
// frame): a stopwatch on the steady clock and the summary of samples (median, p99, max, mean, in ms).
// Numbers to print, never a pass or fail.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <vector>

namespace toposlam::cli {

struct TimingSummary {
  double median_ms = 0, p99_ms = 0, max_ms = 0, mean_ms = 0;
  std::size_t samples = 0;
};

inline TimingSummary summarize(std::vector<double> ms) {
  TimingSummary s;
  if (ms.empty()) return s;
  std::sort(ms.begin(), ms.end());
  s.samples = ms.size();
  s.median_ms = ms[ms.size() / 2];
  s.p99_ms = ms[std::min(ms.size() - 1, static_cast<std::size_t>(std::ceil(0.99 * ms.size())) - 1)];
  s.max_ms = ms.back();
  double total = 0;
  for (double v : ms) total += v;
  s.mean_ms = total / ms.size();
  return s;
}

class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double elapsedMs() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace toposlam::cli
