// The pipeline's status, period by period: what the publisher thread measured since the last status
// (each stage's time per frame, the end-to-end latency, frames published) together with the counters the
// other threads keep (queues, CPU time, places), made into one PipelineStatus. The Pipeline owns one,
// driven by its publisher thread; the collector reads no clock, no atomics and no queues itself (the
// Pipeline hands it a StatusCounters snapshot), so it is tested alone with plain numbers.
//
// Thread-safety: none; one thread (the publisher) uses it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "toposlam/pipeline/bounded_queue.hpp"
#include "toposlam/pipeline/stages.hpp"

namespace toposlam {

/// Median, p99 (nearest rank) and max of `values_ms`; all zero when empty. Reorders `values_ms`.
LatencyStats summarizeLatencies(std::vector<double>& values_ms);

/// The counters a status reads from the rest of the pipeline at the end of a period (all since start).
struct StatusCounters {
  struct Stage {
    std::int64_t processed = 0;  ///< frames the stage finished
    QueueCounters input;         ///< its input queue (none for the capture stage: zeros)
    double cpu_s = 0.0;          ///< CPU time of its thread
  };
  std::vector<Stage> stages;  ///< one per stage, in StatusCollector's order
  double process_cpu_s = 0.0;
  std::int64_t frames_captured = 0;
  std::int64_t source_skipped = 0;
  SkippedFrames source_skipped_by_reason;
  SourceKind source_kind = SourceKind::Camera;
  SourceLink source_link = SourceLink::Streaming;
  std::int64_t source_reconnects = 0;
  int source_reconnect_attempts = 0;
  std::int64_t source_dropped = 0;
  int places = 0;
  std::int64_t place_queue_kept_waits = 0;  ///< the topology stage's place queue was full
  std::int64_t map_revision = 0;
  std::int64_t maps_saved = 0;
  std::int64_t map_save_failures = 0;
  std::string map_save_problem;
};

class StatusCollector {
 public:
  /// `stage_names` name the stages in order; the first period starts at `now_s` with the process's CPU
  /// time `process_cpu_s`. `start_time_s`: when the pipeline started (uptime).
  StatusCollector(std::vector<std::string> stage_names, double start_time_s, double now_s, double process_cpu_s);

  /// A frame published: its stage's own time (ms) for stage `stage`.
  void addStageMs(std::size_t stage, double ms) { stage_ms_.at(stage).push_back(ms); }
  /// A frame published end to end: capture-to-publish latency in ms.
  void addPublished(double latency_ms);
  std::int64_t published() const { return published_; }

  /// True once `period_s` has passed since the period started.
  bool due(double now_s, double period_s) const { return now_s - period_start_s_ >= period_s; }

  /// The status of the period that ends at `now_s` (rates over it, latencies of its frames, totals since
  /// start), in state `state` ("running", "stopping", "finished"); starts the next period.
  PipelineStatus collect(double now_s, const std::string& state, const StatusCounters& counters);

 private:
  std::vector<std::string> names_;
  std::vector<std::vector<double>> stage_ms_;  ///< per stage, this period
  std::vector<double> latency_ms_;             ///< end to end, this period
  std::vector<double> stage_cpu_start_s_;      ///< each stage thread's CPU time at the period's start
  double start_time_s_ = 0.0;
  double period_start_s_ = 0.0;
  double period_cpu_start_s_ = 0.0;
  std::int64_t published_ = 0;
  std::int64_t published_at_period_start_ = 0;
};

}  // namespace toposlam
