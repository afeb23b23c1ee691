// Rate-limited warnings of one kind, with a summary: a folder of 5,000 bad files used to give one log line
// each. The first `first` warnings go out in full; the rest are counted, and one line "<what>: N more
// suppressed (T in all)" goes out at most once per `period_s` while they keep coming, and once more when
// flush() is called (the end of a stream) or the throttle is destroyed, so no count is lost.
// Output and time are injected (a sink for lines, a monotonic clock in seconds), so tests drive both.
// Not thread-safe: one thread at a time (a frame source's next()).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

namespace toposlam {

class WarningThrottle {
 public:
  using Sink = std::function<void(const std::string& line)>;
  using Now = std::function<double()>;  ///< monotonic seconds

  /// `what` names the kind in the summary ("images: skipping bad files"); `first` >= 0 warnings are passed
  /// through; summaries at most every `period_s` seconds (> 0) of `now`.
  WarningThrottle(std::string what, int first, double period_s, Sink sink, Now now);
  ~WarningThrottle();
  WarningThrottle(const WarningThrottle&) = delete;
  WarningThrottle& operator=(const WarningThrottle&) = delete;

  /// One occurrence: passed to the sink if among the first, else counted (and summarised when a period
  /// has gone by since the first warning this summary counts).
  void warn(const std::string& message);
  /// Writes the summary of the warnings suppressed since the last one, if any.
  void flush();

  std::int64_t total() const { return total_; }            ///< warnings seen
  std::int64_t suppressed() const { return suppressed_; }  ///< of them, not passed through
  std::int64_t pending() const { return pending_; }        ///< suppressed and not yet summarised

 private:
  std::string what_;
  int first_;
  double period_s_;
  Sink sink_;
  Now now_;
  std::int64_t total_ = 0;
  std::int64_t suppressed_ = 0;
  std::int64_t pending_ = 0;
  double pending_since_s_ = 0.0;  ///< when the first pending warning came
};

}  // namespace toposlam
