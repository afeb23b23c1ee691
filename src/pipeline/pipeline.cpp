// Pipeline: the five stage threads and the queues between them; see the header for the shape.
#include "toposlam/pipeline/pipeline.hpp"
#include "toposlam/pipeline/frame_failures.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <thread>
#include <utility>

#include <opencv2/core/utility.hpp>
#include <spdlog/spdlog.h>

#include "toposlam/platform/thread_os.hpp"

namespace toposlam {

namespace {

constexpr std::chrono::milliseconds kPollPeriod{100};  // how often an idle thread wakes to beat
// A failed periodic map write is retried after kFirstSaveRetry_s, then after twice as long each time, up to
// map.save_period_s (kMaxSaveRetry_s when there are no periodic saves), unless a newer snapshot comes first.
constexpr double kFirstSaveRetry_s = 1.0;
constexpr double kMaxSaveRetry_s = 60.0;
// The final save (at stop) is tried this many times, kFinalSaveRetry_s apart, before it is an error.
constexpr int kFinalSaveAttempts = 3;
constexpr std::chrono::milliseconds kFinalSaveRetry{500};
const char* const kStageNames[] = {"capture", "fingerprint", "segmentation", "topology", "publisher"};

std::string rangeError(const std::string& key, double value, const char* range) {
  return key + ": " + std::to_string(value) + " is out of range, allowed " + range;
}

}  // namespace

const char* toString(QueueOverflow overflow) {
  switch (overflow) {
    case QueueOverflow::Auto: return "auto";
    case QueueOverflow::Block: return "block";
    case QueueOverflow::DropOldest: break;
  }
  return "drop_oldest";
}

QueueOverflow resolveOverflow(QueueOverflow configured, bool source_real_time) {
  if (configured != QueueOverflow::Auto) return configured;
  return source_real_time ? QueueOverflow::DropOldest : QueueOverflow::Block;
}

std::string PipelineConfig::validate() const {
  const std::pair<const char*, int> capacities[] = {{"queues.frames", queues.frames},
                                                     {"queues.fingerprints", queues.fingerprints},
                                                     {"queues.segmented", queues.segmented},
                                                     {"queues.results", queues.results}};
  for (const auto& [key, capacity] : capacities)
    if (capacity < 1 || capacity > 1024) return rangeError(key, capacity, "1 .. 1024");
  const std::pair<const char*, const ThreadSettings*> thread_table[] = {
      {"threads.capture", &this->threads.capture},       {"threads.fingerprint", &this->threads.fingerprint},
      {"threads.segmentation", &this->threads.segmentation}, {"threads.topology", &this->threads.topology},
      {"threads.publisher", &this->threads.publisher},   {"threads.map_writer", &this->threads.map_writer},
      {"threads.lcm_receiver", &this->threads.lcm_receiver}, {"threads.recorder", &this->threads.recorder}};
  for (const auto& [key, settings] : thread_table)
    if (std::string problem = settings->validate(); !problem.empty()) return std::string(key) + "." + problem;
  if (!(filter_budget_ms >= 0.1 && filter_budget_ms <= 1000.0))
    return rangeError("filter_budget_ms", filter_budget_ms, "0.1 .. 1000 (milliseconds)");
  if (opencv_threads < 0 || opencv_threads > 64) return rangeError("opencv_threads", opencv_threads, "0 .. 64 (threads)");
  if (!(status_period_s >= 0.1 && status_period_s <= 60.0))
    return rangeError("status_period_s", status_period_s, "0.1 .. 60 (seconds)");
  return "";
}

std::string MapConfig::validate() const {
  if (path.size() > 4096) return "path: longer than 4096 characters";
  if (!(save_period_s == 0.0 || (save_period_s >= 1.0 && save_period_s <= 86400.0)))
    return rangeError("save_period_s", save_period_s, "0 (only at stop) or 1 .. 86400 (seconds)");
  if (!(max_mb >= 1.0 && max_mb <= 65536.0)) return rangeError("max_mb", max_mb, "1 .. 65536 (MB)");
  return "";
}

std::string WatchdogConfig::validate() const {
  if (!(heartbeat_timeout_s >= 0.5 && heartbeat_timeout_s <= 600.0))
    return rangeError("heartbeat_timeout_s", heartbeat_timeout_s, "0.5 .. 600 (seconds)");
  return "";
}

std::string statusLine(const PipelineStatus& s) {
  char camera[128];
  if (s.source_kind != SourceKind::Camera)
    std::snprintf(camera, sizeof camera, "%s", sourceActivityText(s.source_kind, s.source_link));
  else if (s.source_link == SourceLink::Reconnecting)
    std::snprintf(camera, sizeof camera, "camera reconnecting (attempt %d, %lld reconnects, %lld lost by the driver)",
                  s.source_reconnect_attempts + 1, static_cast<long long>(s.source_reconnects),
                  static_cast<long long>(s.source_dropped));
  else
    std::snprintf(camera, sizeof camera, "camera streaming (%lld reconnects, %lld lost by the driver)",
                  static_cast<long long>(s.source_reconnects), static_cast<long long>(s.source_dropped));
  char text[384];
  std::snprintf(text, sizeof text,
                "%s: %.1f fps, latency p99 %.1f ms, %d places, map rev %lld, %lld dropped, %lld kept waits; %s",
                s.state.c_str(), s.fps, s.latency.p99_ms, s.places, static_cast<long long>(s.map_revision),
                static_cast<long long>(s.frames_dropped), static_cast<long long>(s.queue_kept_waits), camera);
  std::string line = text;
  if (const std::string skipped = skippedFramesText(s.source_skipped_by_reason); !skipped.empty())
    line += "; " + skipped;
  if (s.map_save_failures > 0)
    line += "; map save failing (" + std::to_string(s.map_save_failures) + " in a row, retrying; the previous map is kept): " +
            s.map_save_problem;
  return line;
}

struct Pipeline::CapturedFrame {
  Frame frame;
  double captured_at_s = 0.0;
};

struct Pipeline::Fingerprinted {
  FrameResult result;
  std::shared_ptr<const Fingerprint> fingerprint;
  cv::Mat thumbnail;
};

struct Pipeline::MapWrite {
  std::shared_ptr<const MapSnapshot> snapshot;
  bool final = false;         ///< the save at stop (its failure is an error, not a warning)
  double snapshot_ms = 0.0;   ///< time the topology thread spent taking it
};

namespace {

/// Records that carry a place are never dropped by the drop-oldest queues (only per-frame estimates).
bool carriesPlace(const FrameResult& r) {
  return r.closed_place.has_value() || !r.finished_places.empty() || r.topology != nullptr || !r.has_frame;
}

}  // namespace

Pipeline::Pipeline(const PipelineConfig& config, const MapConfig& map, const WatchdogConfig& watchdog,
                   FrameSource& source, FingerprintStage& fingerprint, SegmentationStage& segmentation,
                   TopologyStage& topology, PipelineSink& sink, const Clock& clock)
    : config_(config),
      map_(map),
      watchdog_(watchdog),
      source_(source),
      fingerprint_(fingerprint),
      segmentation_(segmentation),
      topology_(topology),
      sink_(sink),
      clock_(clock) {
  const std::pair<const char*, std::string> sections[] = {
      {"pipeline.", config_.validate()}, {"map.", map_.validate()}, {"watchdog.", watchdog_.validate()}};
  for (const auto& [section, problem] : sections)
    if (!problem.empty()) throw std::invalid_argument(section + problem);
  config_.queues.overflow = resolveOverflow(config_.queues.overflow, source_.realTime());
  frames_ = std::make_unique<BoundedQueue<CapturedFrame>>(static_cast<std::size_t>(config_.queues.frames));
  fingerprints_ = std::make_unique<BoundedQueue<Fingerprinted>>(static_cast<std::size_t>(config_.queues.fingerprints));
  segmented_ = std::make_unique<BoundedQueue<FrameResult>>(static_cast<std::size_t>(config_.queues.segmented), carriesPlace);
  results_ = std::make_unique<BoundedQueue<FrameResult>>(static_cast<std::size_t>(config_.queues.results), carriesPlace);
  map_writes_ = std::make_unique<BoundedQueue<MapWrite>>(1);  // a newer snapshot replaces an unwritten one
  status_.state = "created";
}

Pipeline::~Pipeline() {
  requestStop();
  wait();
}

void Pipeline::start() {
  if (started_.exchange(true)) throw std::logic_error("Pipeline::start() called twice");
  start_time_s_ = clock_.now();
  for (auto& h : heartbeat_) h.store(start_time_s_);
  last_frame_fingerprinted_s_.store(start_time_s_);
  last_frame_failed_s_.store(start_time_s_);
  if (config_.record_latencies) latencies_ms_.reserve(1 << 16);
  // Before any stage thread exists: OpenCV's pool must not compete with the table's threads.
  cv::setNumThreads(config_.opencv_threads);
  {
    std::lock_guard lock(status_mutex_);
    status_.state = "running";
  }
  // Started from the end of the chain so every consumer is waiting before its producer runs.
  threads_.start(config_.threads.map_writer, [this] { mapWriterLoop(); });
  threads_.start(config_.threads.publisher, [this] { publisherLoop(); });
  threads_.start(config_.threads.topology, [this] { topologyLoop(); });
  threads_.start(config_.threads.segmentation, [this] { segmentationLoop(); });
  threads_.start(config_.threads.fingerprint, [this] { fingerprintLoop(); });
  threads_.start(config_.threads.capture, [this] { captureLoop(); });
}

void Pipeline::requestStop() {
  stop_requested_.store(true);
  source_.interrupt();  // a camera that sends nothing must not hold the stop up
}

void Pipeline::wait() { threads_.joinAll(); }

double Pipeline::failingWithoutProgressFor(double now) const {
  const double failed = last_frame_failed_s_.load();
  const double passed = last_frame_fingerprinted_s_.load();
  const double timeout = watchdog_.heartbeat_timeout_s;
  // Failing recently (not a camera that sent one bad frame and then went silent: silence is healthy).
  if (failed > passed && now - failed <= timeout && now - passed > timeout) return now - passed;
  return 0.0;
}

bool Pipeline::healthy() const {
  const double now = clock_.now();
  for (int i = 0; i < kThreadCount; ++i)
    if (!thread_done_[i].load() && !waiting_[i].load() && now - heartbeat_[i].load() > watchdog_.heartbeat_timeout_s)
      return false;
  if (!thread_done_[kFingerprint].load() && failingWithoutProgressFor(now) > 0.0) return false;
  return error().empty();
}

std::string Pipeline::stalledStages() const {
  static const char* const kNames[kThreadCount] = {"capture", "fingerprint", "segmentation", "topology", "publisher"};
  const double now = clock_.now();
  std::string out;
  for (int i = 0; i < kThreadCount; ++i) {
    const double silent = now - heartbeat_[i].load();
    if (thread_done_[i].load() || waiting_[i].load() || silent <= watchdog_.heartbeat_timeout_s) continue;
    char item[64];
    std::snprintf(item, sizeof item, "%s%s %.1f s", out.empty() ? "" : ", ", kNames[i], silent);
    out += item;
  }
  if (const double failing = thread_done_[kFingerprint].load() ? 0.0 : failingWithoutProgressFor(now); failing > 0.0) {
    char item[64];
    std::snprintf(item, sizeof item, "%sframes failing %.1f s", out.empty() ? "" : ", ", failing);
    out += item;
  }
  return out;
}

PipelineStatus Pipeline::status() const {
  std::lock_guard lock(status_mutex_);
  return status_;
}

std::string Pipeline::error() const {
  std::lock_guard lock(status_mutex_);
  return error_;
}

void Pipeline::recordError(const std::string& what) {
  spdlog::error("pipeline: {}", what);
  std::lock_guard lock(status_mutex_);
  if (error_.empty()) error_ = what;
}

void Pipeline::beat(StageIndex stage) {
  heartbeat_[stage].store(clock_.now());
  thread_cpu_s_[stage].store(threadCpuSeconds());
}

template <typename Q, typename T>
bool Pipeline::forward(Q& queue, T&& item) {
  if (config_.queues.overflow == QueueOverflow::Block) return queue.pushWait(std::forward<T>(item));
  return queue.push(std::forward<T>(item));
}

void Pipeline::captureLoop() {
  try {
    source_kind_.store(source_.state().kind);
    while (!stop_requested_.load()) {
      Frame frame;
      // Bounded wait: a silent or reconnecting camera still lets this thread beat and see a stop.
      const SourceWait wait = source_.nextFor(kPollPeriod, frame);
      const FrameSourceState state = source_.state();
      if (const std::int64_t skipped = source_.skippedFrames(); skipped > source_skipped_.exchange(skipped)) {
        last_frame_failed_s_.store(clock_.now());  // the source skipped a frame (a bad file, an error buffer)
        const SkippedFrames by_reason = source_.skippedByReason();
        for (std::size_t r = 0; r < kSkipReasonCount; ++r)
          source_skipped_by_reason_[r].store(by_reason.count[r]);
      }
      source_kind_.store(state.kind);
      source_reconnecting_.store(state.link == SourceLink::Reconnecting);
      source_reconnects_.store(state.reconnects);
      source_reconnect_attempts_.store(state.reconnect_attempts);
      source_dropped_.store(state.dropped);
      beat(kCapture);
      if (wait == SourceWait::End) break;
      if (wait == SourceWait::Timeout) continue;
      CapturedFrame captured{std::move(frame), clock_.now()};
      if (!forward(*frames_, std::move(captured))) break;  // downstream ended
      processed_[kCapture].fetch_add(1);
    }
  } catch (const std::exception& e) {
    recordError(std::string("capture: ") + e.what());
  }
  frames_->close();
  thread_done_[kCapture].store(true);
  finished_threads_.fetch_add(1);
}

void Pipeline::fingerprintLoop() {
  FrameFailures failures;  // the one per-frame error policy (frame_failures.hpp)
  try {
    for (;;) {
      CapturedFrame captured;
      setWaiting(kFingerprint, true);
      QueueWait wait = frames_->popFor(captured, kPollPeriod);
      beat(kFingerprint);
      setWaiting(kFingerprint, false);
      if (wait == QueueWait::Closed) break;
      if (wait == QueueWait::Timeout) continue;
      const double t0 = clock_.now();
      Fingerprinted out;
      try {
        FingerprintedFrame made = fingerprint_.process(captured.frame.image, captured.frame.grey);
        out.fingerprint = std::make_shared<const Fingerprint>(std::move(made.fingerprint));
        out.thumbnail = std::move(made.thumbnail);
      } catch (const std::exception& e) {
        // A bad frame from the world: counted, logged now and then, survived.
        if (failures.count())
          spdlog::warn("fingerprint: frame {} skipped ({} so far): {}", captured.frame.sequence, failures.total(), e.what());
        last_frame_failed_s_.store(clock_.now());
        continue;
      }
      last_frame_fingerprinted_s_.store(clock_.now());
      FrameResult& r = out.result;
      r.sequence = captured.frame.sequence;
      r.source_time_s = captured.frame.timestamp_s;
      r.captured_at_s = captured.captured_at_s;
      r.name = std::move(captured.frame.name);
      r.keypoints = out.fingerprint->keypointCount();
      captured = CapturedFrame{};  // hands the buffer back to the source before we queue anything
      r.fingerprint_ms = (clock_.now() - t0) * 1e3;
      if (!forward(*fingerprints_, std::move(out))) break;
      processed_[kFingerprint].fetch_add(1);
    }
  } catch (const std::exception& e) {
    recordError(std::string("fingerprint: ") + e.what());
  }
  frames_->close();  // a dead consumer must not leave the producer blocked
  fingerprints_->close();
  thread_done_[kFingerprint].store(true);
  finished_threads_.fetch_add(1);
}

void Pipeline::segmentationLoop() {
  const bool observes_frames = topology_.observesFrames();  // fixed before the threads start
  try {
    bool input_ended = false;
    for (;;) {
      Fingerprinted in;
      setWaiting(kSegmentation, true);
      QueueWait wait = fingerprints_->popFor(in, kPollPeriod);
      beat(kSegmentation);
      setWaiting(kSegmentation, false);
      if (wait == QueueWait::Closed) {
        input_ended = true;
        break;
      }
      if (wait == QueueWait::Timeout) continue;
      const double t0 = clock_.now();
      if (observes_frames) in.result.fingerprint = in.fingerprint;  // localisation only: the topology stage's
      SegmentationStep step = segmentation_.process(in.result.sequence, in.result.source_time_s, in.result.captured_at_s,
                                                       std::move(in.fingerprint),
                                                       in.thumbnail);
      in.result.lambda2 = step.lambda2;
      in.result.revisit = step.revisit;
      if (step.closed) in.result.closed_place = std::move(step.closed);
      in.result.segmentation_ms = (clock_.now() - t0) * 1e3;
      if (!forward(*segmented_, std::move(in.result))) break;
      processed_[kSegmentation].fetch_add(1);
    }
    // End of stream (not a stop: a resumed run goes on in the same place): the open place closes too,
    // on a record without a frame.
    if (input_ended && !stop_requested_.load()) {
      if (std::optional<ClosedPlace> last = segmentation_.finish()) {
        FrameResult flush;
        flush.has_frame = false;
        flush.closed_place = std::move(last);
        segmented_->pushWait(std::move(flush));
      }
    }
  } catch (const std::exception& e) {
    recordError(std::string("segmentation: ") + e.what());
  }
  fingerprints_->close();
  segmented_->close();
  thread_done_[kSegmentation].store(true);
  finished_threads_.fetch_add(1);
}

void Pipeline::saveMap(bool final) {
  if (map_.path.empty() || !topology_.savesMap()) return;  // localisation only: the map stays as loaded
  const double t0 = clock_.now();
  MapWrite job{topology_.snapshotMap(), final, 0.0};
  job.snapshot_ms = (clock_.now() - t0) * 1e3;
  // Periodic: never wait (an unwritten older snapshot is replaced). At stop: wait for room.
  if (final)
    map_writes_->pushWait(std::move(job));
  else
    map_writes_->push(std::move(job));
}

bool Pipeline::writeMap(const MapWrite& job) {
  const int attempts = job.final ? kFinalSaveAttempts : 1;
  for (int attempt = 1;; ++attempt) {
    const double t0 = clock_.now();
    try {
      job.snapshot->writeTo(map_.path);  // atomic by contract (MapStore: temporary file, fsync, rename)
      maps_saved_.fetch_add(1);
      if (const std::int64_t failed = map_save_failures_.exchange(0); failed > 0)
        spdlog::info("pipeline: the map saves to {} work again after {} failed", map_.path, failed);
      spdlog::info("pipeline: map saved to {} ({} bytes; snapshot {:.2f} ms in the topology thread, encode and write {:.2f} ms "
                   "in the map writer)",
                   map_.path, job.snapshot->bytes(), job.snapshot_ms, (clock_.now() - t0) * 1e3);
      return true;
    } catch (const std::exception& e) {
      const std::int64_t failures = map_save_failures_.fetch_add(1) + 1;
      {
        std::lock_guard lock(status_mutex_);
        map_save_problem_ = e.what();
      }
      if (attempt < attempts) {
        spdlog::warn("pipeline: the final map save to {} failed ({} of {} attempts): {}", map_.path, attempt,
                     attempts, e.what());
        std::this_thread::sleep_for(kFinalSaveRetry * attempt);  // a back-off before trying again
        continue;
      }
      if (job.final)
        recordError("saving the map to " + map_.path + " failed " + std::to_string(attempts) + " times: " + e.what());
      else
        spdlog::warn("pipeline: periodic map save to {} failed ({} in a row; retried, the run goes on): {}", map_.path,
                     failures, e.what());
      return false;
    }
  }
}

void Pipeline::mapWriterLoop() {
  // Encodes and writes snapshots with their fsync here, so neither a big map nor a slow disk holds up the
  // topology thread. A snapshot whose write failed (a full disk, a file-size limit) is written again after a
  // growing wait, unless a newer snapshot comes first and takes its place; the run goes on meanwhile.
  const double max_retry_s = map_.save_period_s > 0 ? map_.save_period_s : kMaxSaveRetry_s;
  std::optional<MapWrite> failed;
  double retry_s = kFirstSaveRetry_s;
  for (;;) {
    MapWrite job;
    if (!failed) {
      std::optional<MapWrite> next = map_writes_->pop();
      if (!next) break;
      job = std::move(*next);
    } else {
      const QueueWait wait = map_writes_->popFor(job, std::chrono::duration<double>(retry_s));
      if (wait == QueueWait::Closed) {
        spdlog::warn("pipeline: the map snapshot whose save to {} failed was not written (no final save came)", map_.path);
        break;
      }
      if (wait == QueueWait::Timeout) job = *failed;
    }
    const bool retry = failed.has_value();
    if (writeMap(job) || job.final) {
      failed.reset();
      retry_s = kFirstSaveRetry_s;
      continue;
    }
    if (retry) retry_s = std::min(retry_s * 2.0, max_retry_s);
    spdlog::info("pipeline: trying the map save again in {:.0f} s", retry_s);
    failed = std::move(job);
  }
  map_writer_done_.set_value();
  finished_threads_.fetch_add(1);
}

void Pipeline::topologyLoop() {
  std::int64_t published_revision = -1;
  double next_save_s = clock_.now() + (map_.save_period_s > 0 ? map_.save_period_s : 0.0);
  const double budget_s = config_.filter_budget_ms * 1e-3;
  std::int64_t place_queue_full = 0;

  // The topology stage's queue is the one place a closed place waits for its step. Bounded: when it is
  // full, the oldest step is finished now, whatever the frame's budget (the frames behind wait, and a
  // drop-oldest queue drops their estimates, counted); counted as a kept wait. Places are never dropped.
  auto enqueueBounded = [&](FrameResult& r, ClosedPlace place) {
    if (topology_.queuedPlaces() >= kPlaceQueueCapacity) {
      place_queue_kept_waits_.fetch_add(1);
      if (place_queue_full++ % 100 == 0)
        spdlog::warn("pipeline: the topology filter is {} places behind; finishing the oldest step now ({} times "
                     "so far)", topology_.queuedPlaces(), place_queue_full);
      while (topology_.queuedPlaces() >= kPlaceQueueCapacity)
        if (std::optional<FinishedPlace> done = topology_.advance(1e9))
          r.finished_places.push_back(std::move(*done));
    }
    topology_.enqueuePlace(std::move(place));
    place_queue_high_water_.store(std::max(place_queue_high_water_.load(), topology_.queuedPlaces()));
  };
  auto stampEstimate = [&](FrameResult& r) {
    r.estimate = topology_.estimate();
    topology_.locate(r.revisit);
    map_revision_.store(r.estimate.map_revision);
    if (r.estimate.map_revision != published_revision) {
      r.topology = std::make_shared<const TopologySnapshot>(topology_.topology());
      published_revision = r.estimate.map_revision;
    }
  };

  bool clean = true;
  try {
    for (;;) {
      FrameResult r;
      setWaiting(kTopology, true);
      QueueWait wait = segmented_->popFor(r, kPollPeriod);
      beat(kTopology);
      setWaiting(kTopology, false);
      if (wait == QueueWait::Closed) break;
      if (wait == QueueWait::Item) {
        const double t0 = clock_.now();
        if (r.closed_place) {
          enqueueBounded(r, std::move(*r.closed_place));
          r.closed_place.reset();
          places_.fetch_add(1);
        }
        // The filter's step is spread over frames: at most budget_s of it per frame.
        const double deadline = t0 + budget_s;
        while (!topology_.idle()) {
          const double remaining = deadline - clock_.now();
          if (remaining <= 0.0) break;
          if (std::optional<FinishedPlace> done = topology_.advance(remaining))
            r.finished_places.push_back(std::move(*done));
        }
        if (r.fingerprint) {  // localisation only: the estimate answers for this frame
          topology_.observeFrame(*r.fingerprint);
          r.fingerprint.reset();
        }
        stampEstimate(r);
        r.filter_ms = (clock_.now() - t0) * 1e3;
        if (!forward(*results_, std::move(r))) break;
        processed_[kTopology].fetch_add(1);
      }
      if (map_.save_period_s > 0 && clock_.now() >= next_save_s && topology_.idle()) {
        try {
          saveMap(false);
        } catch (const std::exception& e) {
          spdlog::warn("pipeline: periodic map snapshot for {} failed: {}", map_.path, e.what());
        }
        next_save_s = clock_.now() + map_.save_period_s;
      }
    }
    // End of stream or stop: finish the steps in progress, publish them on a flush record, save.
    FrameResult flush;
    flush.has_frame = false;
    while (!topology_.idle())
      if (std::optional<FinishedPlace> done = topology_.advance(1e9))
        flush.finished_places.push_back(std::move(*done));
    stampEstimate(flush);
    if (!flush.finished_places.empty() || flush.topology) results_->pushWait(std::move(flush));
  } catch (const std::exception& e) {
    clean = false;
    recordError(std::string("topology: ") + e.what());
  }
  if (clean) {
    try {
      saveMap(true);
    } catch (const std::exception& e) {
      recordError("saving the map to " + map_.path + " failed: " + e.what());
    }
  }
  map_writes_->close();
  map_writer_done_.get_future().wait();  // the map is on disk before the publisher's last status
  segmented_->close();
  results_->close();
  thread_done_[kTopology].store(true);
  finished_threads_.fetch_add(1);
}

StatusCounters Pipeline::statusCounters(std::int64_t published) const {
  StatusCounters c;
  const QueueCounters inputs[kThreadCount] = {QueueCounters{}, frames_->counters(), fingerprints_->counters(),
                                              segmented_->counters(), results_->counters()};
  c.stages.resize(kThreadCount);
  for (int i = 0; i < kThreadCount; ++i) {
    c.stages[static_cast<std::size_t>(i)].processed = i == kPublisher ? published : processed_[i].load();
    c.stages[static_cast<std::size_t>(i)].input = inputs[i];
    c.stages[static_cast<std::size_t>(i)].cpu_s = thread_cpu_s_[i].load();
  }
  c.process_cpu_s = processCpuSeconds();
  c.frames_captured = processed_[kCapture].load();
  c.source_skipped = source_skipped_.load();
  for (std::size_t r = 0; r < kSkipReasonCount; ++r)
    c.source_skipped_by_reason.count[r] = source_skipped_by_reason_[r].load();
  c.source_kind = source_kind_.load();
  c.source_link = source_reconnecting_.load() ? SourceLink::Reconnecting : SourceLink::Streaming;
  c.source_reconnects = source_reconnects_.load();
  c.source_reconnect_attempts = source_reconnect_attempts_.load();
  c.source_dropped = source_dropped_.load();
  c.places = places_.load();
  c.place_queue_kept_waits = place_queue_kept_waits_.load();
  c.map_revision = map_revision_.load();
  c.maps_saved = maps_saved_.load();
  c.map_save_failures = map_save_failures_.load();
  if (c.map_save_failures > 0) {
    std::lock_guard lock(status_mutex_);
    c.map_save_problem = map_save_problem_;
  }
  return c;
}

void Pipeline::publisherLoop() {
  StatusCollector collector(std::vector<std::string>(std::begin(kStageNames), std::end(kStageNames)), start_time_s_,
                            clock_.now(), processCpuSeconds());
  auto emitStatus = [&](const char* state) {
    const double now = clock_.now();
    PipelineStatus s = collector.collect(now, state, statusCounters(collector.published()));
    sink_.publishStatus(s);
    std::lock_guard lock(status_mutex_);
    status_ = std::move(s);
  };

  try {
    for (;;) {
      FrameResult r;
      setWaiting(kPublisher, true);
      QueueWait wait = results_->popFor(r, kPollPeriod);
      beat(kPublisher);
      setWaiting(kPublisher, false);
      if (wait == QueueWait::Item) {
        const double t0 = clock_.now();
        sink_.publish(r);
        const double t1 = clock_.now();
        if (r.has_frame) {
          const double latency_ms = (t1 - r.captured_at_s) * 1e3;
          collector.addStageMs(kFingerprint, r.fingerprint_ms);
          collector.addStageMs(kSegmentation, r.segmentation_ms);
          collector.addStageMs(kTopology, r.filter_ms);
          collector.addStageMs(kPublisher, (t1 - t0) * 1e3);
          collector.addPublished(latency_ms);
          if (config_.record_latencies) latencies_ms_.push_back(latency_ms);
        }
      }
      if (wait == QueueWait::Closed) break;
      if (collector.due(clock_.now(), config_.status_period_s))
        emitStatus(stop_requested_.load() ? "stopping" : "running");
    }
    thread_done_[kPublisher].store(true);
    emitStatus("finished");
  } catch (const std::exception& e) {
    recordError(std::string("publisher: ") + e.what());
  }
  results_->close();
  thread_done_[kPublisher].store(true);
  finished_threads_.fetch_add(1);
}

}  // namespace toposlam
