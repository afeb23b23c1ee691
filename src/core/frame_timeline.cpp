// FrameTimeline: frame timestamps with the steps back cut out; see the header.
#include "toposlam/core/frame_timeline.hpp"

#include <algorithm>
#include <cmath>

namespace toposlam {

double FrameTimeline::typicalIntervalS() const {
  if (interval_count_ == 0) return 1.0;
  std::array<double, kIntervals> sorted = intervals_;
  const auto end = sorted.begin() + interval_count_;
  const auto middle = sorted.begin() + (interval_count_ - 1) / 2;  // the lower median: a gap weighs less
  std::nth_element(sorted.begin(), middle, end);
  return *middle;
}

double FrameTimeline::place(double source_time_s) {
  const bool finite = std::isfinite(source_time_s);
  if (std::isnan(last_s_)) {  // the first frame: the source's own time (0 when it has none)
    last_s_ = finite ? source_time_s : 0.0;
    if (!finite) ++repeated_;
    return last_s_;
  }
  double t = source_time_s + offset_s_;
  if (!finite || !(t > last_s_)) {
    if (finite && t < last_s_) {
      ++steps_back_;
      last_step_back_s_ = last_s_ - t;
    } else {
      ++repeated_;
    }
    t = last_s_ + typicalIntervalS();
    if (!(t > last_s_)) t = std::nextafter(last_s_, HUGE_VAL);  // an interval below the clock's resolution
    if (finite) offset_s_ = t - source_time_s;  // the frames after it keep the source's spacing from here
  }
  intervals_[static_cast<std::size_t>(next_interval_)] = t - last_s_;
  next_interval_ = (next_interval_ + 1) % kIntervals;
  interval_count_ = std::min(interval_count_ + 1, kIntervals);
  last_s_ = t;
  return t;
}

}  // namespace toposlam
