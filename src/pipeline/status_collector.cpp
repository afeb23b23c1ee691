// StatusCollector: a status period's measurements and the pipeline's counters made into PipelineStatus.
#include "toposlam/pipeline/status_collector.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace toposlam {

LatencyStats summarizeLatencies(std::vector<double>& values_ms) {
  LatencyStats stats;
  stats.samples = static_cast<std::int64_t>(values_ms.size());
  if (values_ms.empty()) return stats;
  const std::size_t n = values_ms.size();
  auto at_rank = [&](std::size_t rank) {  // rank-th smallest, from 0
    std::nth_element(values_ms.begin(), values_ms.begin() + static_cast<std::ptrdiff_t>(rank), values_ms.end());
    return values_ms[rank];
  };
  const std::size_t p99_rank = static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(n))) - 1;
  stats.max_ms = *std::max_element(values_ms.begin(), values_ms.end());
  stats.p99_ms = at_rank(p99_rank);
  if (n % 2 == 1) {
    stats.median_ms = at_rank(n / 2);
  } else {
    const double upper = at_rank(n / 2);
    const double lower = *std::max_element(values_ms.begin(), values_ms.begin() + static_cast<std::ptrdiff_t>(n / 2));
    stats.median_ms = 0.5 * (lower + upper);
  }
  return stats;
}

StatusCollector::StatusCollector(std::vector<std::string> stage_names, double start_time_s, double now_s,
                                 double process_cpu_s)
    : names_(std::move(stage_names)),
      stage_ms_(names_.size()),
      stage_cpu_start_s_(names_.size(), 0.0),
      start_time_s_(start_time_s),
      period_start_s_(now_s),
      period_cpu_start_s_(process_cpu_s) {
  // Reserved once for a period's frames (a second at up to ~1000 fps); more only grows them.
  constexpr std::size_t kExpectedFrames = 1024;
  for (auto& w : stage_ms_) w.reserve(kExpectedFrames);
  latency_ms_.reserve(kExpectedFrames);
}

void StatusCollector::addPublished(double latency_ms) {
  ++published_;
  latency_ms_.push_back(latency_ms);
}

PipelineStatus StatusCollector::collect(double now_s, const std::string& state, const StatusCounters& counters) {
  const double elapsed = std::max(1e-9, now_s - period_start_s_);
  PipelineStatus s;
  s.time_s = now_s;
  s.uptime_s = now_s - start_time_s_;
  s.fps = static_cast<double>(published_ - published_at_period_start_) / elapsed;
  s.frames_captured = counters.frames_captured;
  s.frames_published = published_;
  s.source_skipped = counters.source_skipped;
  s.source_skipped_by_reason = counters.source_skipped_by_reason;
  s.source_kind = counters.source_kind;
  s.source_link = counters.source_link;
  s.source_reconnects = counters.source_reconnects;
  s.source_reconnect_attempts = counters.source_reconnect_attempts;
  s.source_dropped = counters.source_dropped;
  s.latency = summarizeLatencies(latency_ms_);
  s.stages.reserve(names_.size());
  for (std::size_t i = 0; i < names_.size(); ++i) {
    const StatusCounters::Stage stage = i < counters.stages.size() ? counters.stages[i] : StatusCounters::Stage{};
    StageStatus st;
    st.name = names_[i];
    st.latency = summarizeLatencies(stage_ms_[i]);
    st.processed = stage.processed;
    st.dropped = stage.input.dropped;
    st.kept_waits = stage.input.kept_waits;
    st.queue_depth = stage.input.depth;
    st.queue_capacity = stage.input.capacity;
    st.cpu_percent = 100.0 * (stage.cpu_s - stage_cpu_start_s_[i]) / elapsed;
    stage_cpu_start_s_[i] = stage.cpu_s;
    s.frames_dropped += stage.input.dropped;
    s.queue_kept_waits += stage.input.kept_waits;
    s.stages.push_back(std::move(st));
  }
  s.queue_kept_waits += counters.place_queue_kept_waits;
  s.cpu_percent = 100.0 * (counters.process_cpu_s - period_cpu_start_s_) / elapsed;
  s.places = counters.places;
  s.map_revision = counters.map_revision;
  s.maps_saved = counters.maps_saved;
  s.map_save_failures = counters.map_save_failures;
  s.map_save_problem = counters.map_save_problem;
  s.state = state;
  for (auto& w : stage_ms_) w.clear();
  latency_ms_.clear();
  period_start_s_ = now_s;
  period_cpu_start_s_ = counters.process_cpu_s;
  published_at_period_start_ = published_;
  return s;
}

}  // namespace toposlam
