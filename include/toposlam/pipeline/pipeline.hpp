// The real-time pipeline: five named stage threads and a map writer, created at start and joined at stop,
//
//   capture --q--> fingerprint --q--> segmentation --q--> topology --q--> publisher
//                                                         (places q)
//                                                            `--snapshot--> map writer
//
// connected by BoundedQueues. When a stage falls behind, its input queue drops the OLDEST per-frame item
// and counts it (overflow: drop_oldest, the real-time default), or the producer waits (overflow: block,
// for lossless replay of files). Records that carry a place (a closed place, a finished step, a new
// topology) are never dropped. Frames are not copied: the capture queue carries the source's Frame (its
// buffer_lease keeps the driver buffer); the fingerprint thread releases it as soon as the fingerprint
// stage has made the fingerprint and a small thumbnail (FingerprintedFrame). The topology filter's step for
// a place is spread over the following frames: per frame the topology thread spends at most
// `filter_budget_ms` in TopologyStage::advance(). A status is published every `status_period_s`. The map
// is saved atomically every `MapConfig::save_period_s` and at stop: the topology thread takes an in-memory
// snapshot, the map writer thread writes it (fsync off the frame path). A write that fails is retried
// with a growing wait (a newer snapshot takes its place), counted in the status (map_save_failures) while
// the run goes on; the final save is tried three times before it is the pipeline's error.
//
// The capture thread reads the source with a bounded wait (FrameSource::nextFor), so it keeps beating
// while a camera is silent or reconnecting: that is healthy, and the status says "reconnecting". A stage
// thread waiting for input is healthy too; only a thread stuck inside its work for the watchdog's
// heartbeat_timeout_s (a stalled pipeline) makes healthy() false. So does a pipeline that is busy without
// progress: frames keep arriving but every one fails (skipped by the source, e.g. V4L2 error buffers, or
// refused by the fingerprint stage) and none has been fingerprinted for heartbeat_timeout_s.
// requestStop() interrupts the source.
//
// Thread-safety: start(), requestStop() and wait() from the owning thread; status(), healthy(),
// finished() from any thread.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <future>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "toposlam/pipeline/bounded_queue.hpp"
#include "toposlam/pipeline/clock.hpp"
#include "toposlam/pipeline/frame_source.hpp"
#include "toposlam/pipeline/stages.hpp"
#include "toposlam/pipeline/status_collector.hpp"
#include "toposlam/pipeline/thread_table.hpp"

namespace toposlam {

/// What a full queue does. Auto: DropOldest for a source that runs in real time (a camera, a file played
/// with ?rate=, FrameSource::realTime()), Block for one that does not (files and the simulator played as
/// fast as the pipeline goes: dropping their frames would only lose them).
enum class QueueOverflow { Auto, DropOldest, Block };
const char* toString(QueueOverflow overflow);
/// Auto resolved for a source that is (or is not) real time; the other values unchanged.
QueueOverflow resolveOverflow(QueueOverflow configured, bool source_real_time);

struct PipelineQueues {
  int frames = 2;         ///< capture -> fingerprint (frames hold camera buffers: keep small)
  int fingerprints = 8;   ///< fingerprint -> segmentation
  int segmented = 8;      ///< segmentation -> topology
  int results = 16;       ///< topology -> publisher
  QueueOverflow overflow = QueueOverflow::Auto;
};

struct PipelineThreads {
  ThreadSettings capture{"tsl-capture"};
  ThreadSettings fingerprint{"tsl-fingerprint"};
  ThreadSettings segmentation{"tsl-segment"};
  ThreadSettings topology{"tsl-topology"};
  ThreadSettings publisher{"tsl-publish"};
  ThreadSettings map_writer{"tsl-mapsave"};
  /// The daemon's two I/O threads, started beside the Pipeline's (toposlamd): the LCM receiver (motion
  /// input) and, with record.dir, the recording's writer (nice 10: it yields to the stage threads).
  ThreadSettings lcm_receiver{"tsl-lcm-rx"};
  ThreadSettings recorder{"tsl-record", -1, SchedulingPolicy::Other, 0, 10};
};

/// pipeline.*: queues, threads, budgets.
struct PipelineConfig {
  PipelineQueues queues;
  PipelineThreads threads;
  double filter_budget_ms = 5.0;     ///< topology work per frame, milliseconds (0.1 .. 1000)
  double status_period_s = 1.0;      ///< status message period (0.1 .. 60)
  bool record_latencies = false;     ///< keep every frame's capture-to-publish latency (benchmark)
  /// OpenCV's own thread pool, set at start (cv::setNumThreads, process-wide). 1: OpenCV runs each call
  /// on the calling stage thread, so the only threads are the table's and the fingerprint workers
  /// (docs/performance.md, "OpenCV's threads"). 0 .. 64; 0 is OpenCV's "sequential" too.
  int opencv_threads = 1;
  /// "" or "<key>: <problem, allowed range>" with keys relative to the pipeline section.
  std::string validate() const;
};

/// map.*: the map file. The Pipeline saves it (path, save_period_s); toposlamd decides at start what it
/// loads (load_at_start, resume_other_source, resume_other_settings, source_from_start, max_mb).
/// map.mode: build the map (and resume it), or localise in a saved map that never changes.
enum class MapMode { Map, Localize };

/// map.localize.*: the localisation-only mode's settings (NodeLocalizer; docs/daemon.md).
struct MapLocalizeConfig {
  double min_probability = 0.5;  ///< a frame's best node under this belief answers "not a known node"
  double jump_weight = 0.01;     ///< weight of moving to any node off the map's edges (relocalisation)
};

struct MapConfig {
  MapMode mode = MapMode::Map;  ///< map.mode
  MapLocalizeConfig localize;   ///< map.localize.*
  std::string path;  ///< map.path: where the map is saved; empty = never saved
  /// map.save_period_s: periodic save, seconds (0 = only at stop; else 1 .. 86400)
  double save_period_s = 60.0;
  bool load_at_start = true;  ///< map.load_at_start: resume from `path` if it exists
  /// map.resume_other_source: resume a map recorded from another source (else refused, exit 2)
  bool resume_other_source = false;
  /// map.resume_other_settings: resume a map made with other decision settings (else refused, exit 2)
  bool resume_other_settings = false;
  /// map.source_from_start: a resumed map's images: source starts from its first frame, not after the
  /// last frame the map holds
  bool source_from_start = false;
  double max_mb = 256;  ///< map.max_mb: a bigger map file is refused unread, 1 .. 65536 MB
  /// "" or "<key>: <problem, allowed range>" with keys relative to the map section.
  std::string validate() const;
};

/// watchdog.*: the Pipeline's heartbeat (healthy()) and toposlamd's systemd watchdog pings.
struct WatchdogConfig {
  bool enabled = true;               ///< watchdog.enabled: ping systemd while the pipeline is healthy
  double heartbeat_timeout_s = 5.0;  ///< a thread silent this long makes healthy() false (0.5 .. 600)
  /// "" or "<key>: <problem, allowed range>" with keys relative to the watchdog section.
  std::string validate() const;
};

/// One line for systemd's STATUS= and the log: "running: 29.8 fps, latency p99 12.0 ms, 4 places, map rev 4,
/// 0 dropped; camera streaming (0 reconnects, 0 lost by the driver)"; while the camera is away the camera
/// part reads "camera reconnecting (attempt N, ...)".
std::string statusLine(const PipelineStatus& status);


class Pipeline {
 public:
  /// The pipeline copies the three configs and borrows the rest; all must outlive it. Throws
  /// std::invalid_argument naming the key ("pipeline.queues.frames: ...") on a bad config.
  Pipeline(const PipelineConfig& config, const MapConfig& map, const WatchdogConfig& watchdog,
           FrameSource& source, FingerprintStage& fingerprint, SegmentationStage& segmentation,
           TopologyStage& topology, PipelineSink& sink, const Clock& clock);
  ~Pipeline();  ///< requests stop and joins
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  /// Creates the threads. Call once.
  void start();
  /// Stops taking frames from the source (and interrupts a source waiting for a frame); frames already
  /// inside drain, the filter step in progress finishes, the map is saved, then the threads end. Returns
  /// immediately (async-signal-unsafe: call it from a normal thread, not a signal handler).
  void requestStop();
  /// Joins the threads (returns when the source ended or after requestStop()).
  void wait();
  /// True once every thread has ended (end of stream or stop).
  bool finished() const { return finished_threads_.load() == kThreadCount + 1; }
  /// False when a running stage thread has been inside its work (not waiting for input or a frame) for
  /// the watchdog's heartbeat_timeout_s, when frames keep failing and none was fingerprinted for
  /// heartbeat_timeout_s, or a stage failed (watchdog food). A camera away or silent is healthy.
  bool healthy() const;
  /// What makes healthy() false, as "capture 6.0 s, topology 7.5 s" (stage threads, seconds since their
  /// last heartbeat) and "frames failing 6.0 s" (none fingerprinted meanwhile); "" when nothing. The
  /// daemon puts it in its STATUS= so a stall that withholds the watchdog pings says where it is.
  std::string stalledStages() const;
  /// The last status published (updated every status period by the publisher thread).
  PipelineStatus status() const;
  /// Every frame's capture-to-publish latency in ms, in publish order (record_latencies only; after wait()).
  const std::vector<double>& latencies() const { return latencies_ms_; }
  /// Thread priority/pinning problems met at start and exceptions that ended a thread.
  std::vector<std::string> warnings() const { return threads_.warnings(); }
  /// Error that ended a stage thread ("" if none); the daemon exits non-zero on it.
  std::string error() const;
  /// What a full queue does in this run: queues.overflow with Auto resolved for the source.
  QueueOverflow overflow() const { return config_.queues.overflow; }

  /// Places that may wait in the topology stage's queue (TopologyStage::queuedPlaces, the one in its step
  /// included). A place closed when it is full first has the oldest step finished, beyond the frame's
  /// budget (a kept wait, PipelineStatus::queue_kept_waits): the filter may fall behind by this many places,
  /// no more; places are never dropped.
  static constexpr std::size_t kPlaceQueueCapacity = 16;
  /// Most places the topology stage's queue held at once (any thread).
  std::size_t placeQueueHighWater() const { return place_queue_high_water_.load(); }

 private:
  struct CapturedFrame;
  struct Fingerprinted;
  struct MapWrite;
  static constexpr int kThreadCount = 5;  ///< stage threads (the map writer is counted apart)
  enum StageIndex { kCapture = 0, kFingerprint, kSegmentation, kTopology, kPublisher };

  void captureLoop();
  void fingerprintLoop();
  void segmentationLoop();
  void topologyLoop();
  void publisherLoop();
  /// The counters a status reads (publisher thread); `published`: the publisher's own count.
  StatusCounters statusCounters(std::int64_t published) const;
  void mapWriterLoop();
  /// Writes one snapshot (map writer thread): true when it is on disk; a failure is counted, logged and
  /// kept for the status (the final save is tried kFinalSaveAttempts times before it is an error).
  bool writeMap(const MapWrite& job);
  /// Snapshot now (topology thread, when idle) and hand it to the map writer; `final` at stop.
  void saveMap(bool final);
  void beat(StageIndex stage);
  /// A stage waiting on its input queue (true) or working on an item (false).
  void setWaiting(StageIndex stage, bool waiting) { waiting_[stage].store(waiting); }
  void recordError(const std::string& what);
  /// Pushes by the overflow policy; false when the queue was closed (downstream ended).
  template <typename Q, typename T>
  bool forward(Q& queue, T&& item);

  PipelineConfig config_;
  MapConfig map_;
  WatchdogConfig watchdog_;
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
  std::unique_ptr<BoundedQueue<MapWrite>> map_writes_;
  std::promise<void> map_writer_done_;  ///< set when the map writer has written its last snapshot

  ThreadTable threads_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<int> finished_threads_{0};
  std::atomic<bool> started_{false};
  double start_time_s_ = 0.0;
  std::atomic<double> heartbeat_[kThreadCount] = {};
  std::atomic<bool> thread_done_[kThreadCount] = {};
  std::atomic<bool> waiting_[kThreadCount] = {};
  std::atomic<std::int64_t> processed_[kThreadCount] = {};
  std::atomic<double> thread_cpu_s_[kThreadCount] = {};  ///< CPU time of each stage thread so far
  std::atomic<std::int64_t> maps_saved_{0};
  std::atomic<std::int64_t> map_save_failures_{0};  ///< failed map writes since the last one that succeeded
  std::string map_save_problem_;                    ///< the last failure's message (status_mutex_)
  std::atomic<int> places_{0};
  std::atomic<std::int64_t> place_queue_kept_waits_{0};  ///< the place queue was full (topology thread)
  std::atomic<std::size_t> place_queue_high_water_{0};
  // Copied by their owning thread so the publisher never calls into another thread's stage or source.
  std::atomic<std::int64_t> map_revision_{0};
  std::atomic<std::int64_t> source_skipped_{0};
  std::array<std::atomic<std::int64_t>, kSkipReasonCount> source_skipped_by_reason_{};  ///< by SkipReason
  /// Clock times of the last frame that failed (skipped by the source or refused by the fingerprint
  /// stage) and of the last one fingerprinted: frames failing with none passing is no progress.
  std::atomic<double> last_frame_failed_s_{0.0};
  std::atomic<double> last_frame_fingerprinted_s_{0.0};
  /// Seconds without a fingerprinted frame while frames keep failing (within heartbeat_timeout_s); 0 when
  /// frames pass, none arrive, or not yet heartbeat_timeout_s.
  double failingWithoutProgressFor(double now) const;
  std::atomic<bool> source_reconnecting_{false};
  std::atomic<SourceKind> source_kind_{SourceKind::Camera};
  std::atomic<std::int64_t> source_reconnects_{0};
  std::atomic<int> source_reconnect_attempts_{0};
  std::atomic<std::int64_t> source_dropped_{0};

  mutable std::mutex status_mutex_;
  PipelineStatus status_;
  std::string error_;
  std::vector<double> latencies_ms_;
};

}  // namespace toposlam
