// SteadyClock: std::chrono::steady_clock in seconds; see the header.
#include "toposlam/pipeline/clock.hpp"

#include <chrono>

namespace toposlam {

double SteadyClock::now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace toposlam
