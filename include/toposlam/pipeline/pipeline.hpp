// The real-time pipeline: five named threads created at start and joined at stop,
//
//   capture --q--> fingerprint --q--> segmentation --q--> topology --q--> publisher
//
// connected by BoundedQueues. When a stage falls behind, its input queue drops the OLDEST item and counts
// it (overflow: drop_oldest, the real-time default), or the producer waits (overflow: block, for lossless
// replay of files). Frames are not copied: the capture queue carries the source's Frame (its buffer_lease
// keeps the driver buffer); the fingerprint thread releases it as soon as the fingerprint and a small
// thumbnail are made. The topology filter's step for a place is spread over the following frames: per
// frame the topology thread spends at most `filter_budget_ms` in TopologyStage::advance(). A status is
// published every `status_period_s`. The map is saved atomically (temporary file + rename) every
// `map_save_period_s` and at stop.
//
// Thread-safety: start(), requestStop() and wait() from the owning thread; status(), healthy(),
// finished() from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "toposlam/io/frame_source.hpp"
#include "toposlam/pipeline/bounded_queue.hpp"
#include "toposlam/pipeline/clock.hpp"
#include "toposlam/pipeline/stages.hpp"
#include "toposlam/pipeline/thread_table.hpp"

namespace toposlam {

enum class QueueOverflow { DropOldest, Block };
const char* toString(QueueOverflow overflow);

struct PipelineQueues {
  int frames = 2;         ///< capture -> fingerprint (frames hold camera buffers: keep small)
  int fingerprints = 8;   ///< fingerprint -> segmentation
  int segmented = 8;      ///< segmentation -> topology
  int results = 16;       ///< topology -> publisher
  QueueOverflow overflow = QueueOverflow::DropOldest;
};

struct PipelineThreads {
  ThreadSettings capture{"tsl-capture"};
  ThreadSettings fingerprint{"tsl-fingerprint"};
  ThreadSettings segmentation{"tsl-segment"};
  ThreadSettings topology{"tsl-topology"};
  ThreadSettings publisher{"tsl-publish"};
};

struct PipelineConfig {
  PipelineQueues queues;
  PipelineThreads threads;
  double filter_budget_ms = 5.0;     ///< topology work per frame, milliseconds (0.1 .. 1000)
  double status_period_s = 1.0;      ///< status message period (0.1 .. 60)
  int thumbnail_width = 160;         ///< place-event thumbnail width in pixels (16 .. 1280), height keeps aspect
  std::string map_path;              ///< where the map is saved; empty = never saved
  double map_save_period_s = 60.0;   ///< periodic save, seconds (0 = only at stop; else 1 .. 86400)
  double heartbeat_timeout_s = 5.0;  ///< a thread silent this long makes healthy() false (0.5 .. 600)
  bool record_latencies = false;     ///< keep every frame's capture-to-publish latency (benchmark)
  /// "" or "<key>: <problem, allowed range>" with keys relative to the pipeline section.
  std::string validate() const;
};

/// Median, p99 (nearest rank) and max of `values_ms`; all zero when empty. Reorders `values_ms`.
LatencyStats summarizeLatencies(std::vector<double>& values_ms);

class Pipeline {
 public:
  /// The pipeline borrows everything; all must outlive it. Throws std::invalid_argument on a bad config.
  Pipeline(const PipelineConfig& config, FrameSource& source, FingerprintStage& fingerprint,
           SegmentationStage& segmentation, TopologyStage& topology, PipelineSink& sink, const Clock& clock);
  ~Pipeline();  ///< requests stop and joins
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  /// Creates the threads. Call once.
  void start();
  /// Stops taking frames from the source; frames already inside drain, the filter step in progress
  /// finishes, the map is saved, then the threads end. Returns immediately (async-signal-unsafe: call it
  /// from a normal thread, not a signal handler).
  void requestStop();
  /// Joins the threads (returns when the source ended or after requestStop()).
  void wait();
  /// True once every thread has ended (end of stream or stop).
  bool finished() const { return finished_threads_.load() == kThreadCount; }
  /// False when a running thread has not shown progress for heartbeat_timeout_s (watchdog food).
  bool healthy() const;
  /// The last status published (updated every status period by the publisher thread).
  PipelineStatus status() const;
  /// Every frame's capture-to-publish latency in ms, in publish order (record_latencies only; after wait()).
  const std::vector<double>& latencies() const { return latencies_ms_; }
  /// Thread priority/pinning problems met at start and exceptions that ended a thread.
  std::vector<std::string> warnings() const { return threads_.warnings(); }
  /// Error that ended a stage thread ("" if none); the daemon exits non-zero on it.
  std::string error() const;

 private:
  struct CapturedFrame;
  struct Fingerprinted;
  static constexpr int kThreadCount = 5;
  enum StageIndex { kCapture = 0, kFingerprint, kSegmentation, kTopology, kPublisher };

  void captureLoop();
  void fingerprintLoop();
  void segmentationLoop();
  void topologyLoop();
  void publisherLoop();
  void saveMap();
  void beat(StageIndex stage);
  void recordError(const std::string& what);
  /// Pushes by the overflow policy; false when the queue was closed (downstream ended).
  template <typename Q, typename T>
  bool forward(Q& queue, T&& item);

  PipelineConfig config_;
  FrameSource& source_;
  FingerprintStage& fingerprint_;
  SegmentationStage& segmentation_;
  TopologyStage& topology_;
  PipelineSink& sink_;
  const Clock& clock_;

  std::unique_ptr<BoundedQueue<CapturedFrame>> frames_;
  std::unique_ptr<BoundedQueue<Fingerprinted>> fingerprints_;
  std::unique_ptr<BoundedQueue<FrameResult>> segmented_;
  std::unique_ptr<BoundedQueue<FrameResult>> results_;

  ThreadTable threads_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<int> finished_threads_{0};
  std::atomic<bool> started_{false};
  double start_time_s_ = 0.0;
  std::atomic<double> heartbeat_[kThreadCount] = {};
  std::atomic<bool> thread_done_[kThreadCount] = {};
  std::atomic<std::int64_t> processed_[kThreadCount] = {};
  std::atomic<double> thread_cpu_s_[kThreadCount] = {};  ///< CPU time of each stage thread so far
  std::atomic<std::int64_t> maps_saved_{0};
  std::atomic<int> places_{0};
  // Copied by their owning thread so the publisher never calls into another thread's stage or source.
  std::atomic<std::int64_t> map_revision_{0};
  std::atomic<std::int64_t> source_skipped_{0};

  mutable std::mutex status_mutex_;
  PipelineStatus status_;
  std::string error_;
  std::vector<double> latencies_ms_;
};

}  // namespace toposlam
