// WarningThrottle (warning_throttle.hpp): the first few warnings in full, then periodic and final summaries.
#include "toposlam/core/warning_throttle.hpp"

#include <stdexcept>
#include <utility>

namespace toposlam {

WarningThrottle::WarningThrottle(std::string what, int first, double period_s, Sink sink, Now now)
    : what_(std::move(what)),
      first_(first),
      period_s_(period_s),
      sink_(std::move(sink)),
      now_(std::move(now)) {
  if (first_ < 0 || !(period_s_ > 0) || !sink_ || !now_)
    throw std::invalid_argument("WarningThrottle: first >= 0, period_s > 0, a sink and a clock are needed");
}

WarningThrottle::~WarningThrottle() {
  try {
    flush();
  } catch (...) {  // a sink that throws at destruction loses the last summary, nothing else
  }
}

void WarningThrottle::warn(const std::string& message) {
  ++total_;
  if (total_ <= first_) {
    sink_(total_ == first_ ? message + " (" + what_ + ": further ones are counted and summarised)" : message);
    return;
  }
  ++suppressed_;
  const double now_s = now_();
  if (pending_++ == 0) pending_since_s_ = now_s;
  if (now_s - pending_since_s_ >= period_s_) flush();
}

void WarningThrottle::flush() {
  if (pending_ == 0) return;
  const std::int64_t pending = pending_;
  pending_ = 0;
  sink_(what_ + ": " + std::to_string(pending) + " more suppressed (" + std::to_string(total_) + " in all)");
}

}  // namespace toposlam
