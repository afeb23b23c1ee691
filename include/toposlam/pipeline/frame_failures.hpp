// The one per-frame error policy of every frame loop (toposlamd's fingerprint thread, `toposlam map` and
// `segment`): bad input from the world is counted, said now and then, and survived.
#pragma once

#include <cstdint>

namespace toposlam {

/// The per-frame error policy of every frame loop: a frame the stages throw on (a corrupt, empty or too
/// small image: bad input from the world) is skipped and counted, and said on the first and every 100th
/// one; the run goes on.
class FrameFailures {
 public:
  /// Counts one; true when this one is to be said (logged).
  bool count() { return failures_++ % 100 == 0; }
  std::int64_t total() const { return failures_; }

 private:
  std::int64_t failures_ = 0;
};

}  // namespace toposlam
