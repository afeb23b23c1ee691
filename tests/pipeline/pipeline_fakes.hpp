// Fake stages for pipeline tests: a counting frame source, a camera that is away (reconnecting) or hangs,
// a fingerprint stage with hooks, a segmentation that closes a place every N frames, and a topology filter
// whose step costs a fixed number of slices of manual-clock time (so "spread over frames" is exact and
// needs no wall clock).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "toposlam/pipeline/clock.hpp"
#include "toposlam/pipeline/stages.hpp"

namespace toposlam::test {

class FakeSource final : public FrameSource {
 public:
  /// count < 0: endless.
  explicit FakeSource(std::int64_t count) : count_(count) {}
  std::string describe() const override { return "fake"; }
  void interrupt() override { interrupted.store(true); }
  bool realTime() const override { return real_time; }
  std::int64_t skippedFrames() const override { return skipped.total(); }
  SkippedFrames skippedByReason() const override { return skipped; }
  std::optional<Frame> next() override {
    if (interrupted.load()) return std::nullopt;
    if (count_ >= 0 && produced_ >= count_) {
      if (on_end) on_end();
      return std::nullopt;
    }
    if (before_frame) before_frame(produced_);
    Frame f;
    f.image = cv::Mat(24, 32, CV_8UC3, cv::Scalar::all(static_cast<double>(produced_ % 256)));
    f.sequence = produced_;
    f.timestamp_s = static_cast<double>(produced_) / 30.0;
    f.name = std::to_string(produced_);
    // The lease stands for a driver buffer: its release is counted.
    f.buffer_lease = std::shared_ptr<void>(nullptr, [this](void*) { released.fetch_add(1); });
    ++produced_;
    return f;
  }
  std::function<void(std::int64_t)> before_frame;
  std::function<void()> on_end;
  bool real_time = false;  ///< what realTime() says (a camera, a file played with ?rate=)
  SkippedFrames
      skipped;  ///< what skippedByReason() says; change it only from before_frame (the capture thread)
  std::atomic<int> released{0};
  std::atomic<bool> interrupted{false};

 private:
  std::int64_t count_;
  std::int64_t produced_ = 0;
};

/// A camera that delivers nothing. `Mode::Reconnecting`: every nextFor() waits its timeout (woken by
/// interrupt()) and reports no frame, with state() saying reconnecting, like V4l2FrameSource while the
/// camera is unplugged. `Mode::Hung`: nextFor() ignores its timeout and blocks until interrupt(), like a
/// driver call that never returns. Counts the calls so a test can wait for the capture thread to loop.
class AbsentCameraSource final : public FrameSource {
 public:
  enum class Mode { Reconnecting, Hung };
  explicit AbsentCameraSource(Mode mode) : mode_(mode) {}
  std::string describe() const override { return "absent camera"; }
  std::optional<Frame> next() override {
    Frame frame;
    while (nextFor(std::chrono::milliseconds(100), frame) == SourceWait::Timeout) {
    }
    return std::nullopt;
  }
  SourceWait nextFor(std::chrono::milliseconds timeout, Frame&) override {
    std::unique_lock lock(mutex_);
    ++calls_;
    changed_.notify_all();
    if (mode_ == Mode::Hung)
      changed_.wait(lock, [&] { return interrupted_; });
    else
      changed_.wait_for(lock, timeout, [&] { return interrupted_; });
    return interrupted_ ? SourceWait::End : SourceWait::Timeout;
  }
  void interrupt() override {
    std::lock_guard lock(mutex_);
    interrupted_ = true;
    changed_.notify_all();
  }
  FrameSourceState state() const override {
    FrameSourceState s;
    s.link = mode_ == Mode::Reconnecting ? SourceLink::Reconnecting : SourceLink::Streaming;
    s.reconnect_attempts = 4;
    s.reconnects = 2;
    s.dropped = 7;
    return s;
  }
  /// Blocks until nextFor() has been entered `n` times in all.
  void waitForCalls(int n) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return calls_ >= n; });
  }
  int calls() {
    std::lock_guard lock(mutex_);
    return calls_;
  }

 private:
  Mode mode_;
  std::mutex mutex_;
  std::condition_variable changed_;
  int calls_ = 0;
  bool interrupted_ = false;
};

class FakeFingerprint final : public FingerprintStage {
 public:
  FingerprintedFrame process(const cv::Mat& image, const cv::Mat& /*grey*/) override {
    const int value = image.at<cv::Vec3b>(0, 0)[0];
    if (on_process) on_process(value);
    if (throw_when && throw_when(value)) throw std::invalid_argument("unreadable frame");
    FingerprintedFrame f;
    f.fingerprint.image_width = image.cols;
    f.fingerprint.image_height = image.rows;
    // A 2x1 thumbnail whose pixels say which frame it was made of (sequence % 256).
    f.thumbnail = cv::Mat(1, 2, CV_8UC3, cv::Scalar::all(static_cast<double>(value)));
    return f;
  }
  std::function<void(int)> on_process;   ///< argument: the frame's pixel value (sequence % 256)
  std::function<bool(int)> throw_when;
};

class FakeSegmentation final : public SegmentationStage {
 public:
  explicit FakeSegmentation(int period) : period_(period) {}
  SegmentationStep process(std::int64_t sequence, double /*source_time_s*/, double /*captured_at_s*/,
                           std::shared_ptr<const Fingerprint> fingerprint, const cv::Mat& thumbnail) override {
    if (throw_at >= 0 && sequence == throw_at) throw std::runtime_error("boom");
    if (after_frame) after_frame(sequence);
    SegmentationStep step;
    step.lambda2 = static_cast<double>(sequence);
    last_sequence_ = sequence;
    last_fingerprint_ = fingerprint;
    if ((sequence + 1) % period_ == 0) {
      ClosedPlace p;
      p.place = closed++;
      p.first_frame = sequence - period_ + 1;
      p.last_frame = sequence;
      p.representative_frame = sequence - period_ / 2;
      p.representative = std::move(fingerprint);
      p.thumbnail = thumbnail;
      step.closed = std::move(p);
    }
    return step;
  }
  /// Closes the frames since the last full block as one (shorter) place.
  std::optional<ClosedPlace> finish() override {
    ++finish_calls;
    if (last_sequence_ < 0 || (last_sequence_ + 1) % period_ == 0) return std::nullopt;
    ClosedPlace p;
    p.place = closed++;
    p.first_frame = last_sequence_ - last_sequence_ % period_;
    p.last_frame = last_sequence_;
    p.representative_frame = last_sequence_;
    p.representative = last_fingerprint_;
    return p;
  }
  int closed = 0;
  int finish_calls = 0;
  std::int64_t throw_at = -1;
  std::function<void(std::int64_t)> after_frame;  ///< called with each frame's sequence

 private:
  int period_;
  std::int64_t last_sequence_ = -1;
  std::shared_ptr<const Fingerprint> last_fingerprint_;
};

class FakeTopology final : public TopologyStage {
 public:
  FakeTopology(ManualClock& clock, int slices_per_step, double slice_s)
      : clock_(clock), slices_per_step_(slices_per_step), slice_s_(slice_s) {}
  void enqueuePlace(ClosedPlace place) override {
    queue_.push_back(std::move(place));
    most_queued = std::max(most_queued, queue_.size());
  }
  std::optional<FinishedPlace> advance(double budget_s) override {
    const double deadline = clock_.now() + budget_s;
    do {
      if (queue_.empty()) return std::nullopt;
      clock_.advance(slice_s_);  // one slice of work costs slice_s of (manual) time
      if (++done_slices_ == slices_per_step_) {
        done_slices_ = 0;
        FinishedPlace done{std::move(queue_.front()), PlaceAssignment{}};
        queue_.pop_front();
        const int place = done.place.place;
        ++revision_;
        estimate_.place = place;
        estimate_.node = place % 3;  // a loop of three rooms
        estimate_.is_new = place < 3;
        estimate_.probability = 0.9;
        estimate_.map_revision = revision_;
        done.assignment = PlaceAssignment{place, estimate_.node, estimate_.is_new, 0.9};
        return done;
      }
    } while (clock_.now() < deadline);
    return std::nullopt;
  }
  std::size_t queuedPlaces() const override { return queue_.size(); }
  bool idle() const override { return queue_.empty(); }
  const PlaceEstimate& estimate() const override { return estimate_; }
  TopologySnapshot topology() const override {
    TopologySnapshot t;
    t.map_revision = revision_;
    return t;
  }
  /// The snapshot records when it was taken; its write records where (on the map writer thread).
  class Snapshot final : public MapSnapshot {
   public:
    Snapshot(const FakeTopology& owner, bool idle, std::int64_t revision)
        : owner_(owner), idle_(idle), revision_(revision) {}
    void writeTo(const std::string& path) const override {
      if (owner_.on_write) owner_.on_write();
      std::lock_guard lock(owner_.saves_mutex);
      owner_.saves.push_back(path);
      owner_.saved_while_idle.push_back(idle_);
      owner_.saved_at_revision.push_back(revision_);
    }
    std::size_t bytes() const override { return 8; }

   private:
    const FakeTopology& owner_;
    bool idle_;
    std::int64_t revision_;
  };
  std::unique_ptr<const MapSnapshot> snapshotMap() const override {
    return std::make_unique<Snapshot>(*this, idle(), revision_);
  }
  std::function<void()> on_write;  ///< called on the map writer thread before each write (e.g. a slow disk)
  std::size_t most_queued = 0;     ///< most places queued at once (topology thread; read after wait())
  mutable std::mutex saves_mutex;
  mutable std::vector<std::string> saves;
  mutable std::vector<bool> saved_while_idle;
  mutable std::vector<std::int64_t> saved_at_revision;

 private:
  ManualClock& clock_;
  int slices_per_step_;
  double slice_s_;
  std::deque<ClosedPlace> queue_;
  int done_slices_ = 0;
  std::int64_t revision_ = 0;
  PlaceEstimate estimate_;
};

/// Records everything; can wake a waiting test after N frames.
class RecordingSink final : public PipelineSink {
 public:
  void publish(const FrameResult& r) override {
    if (before_publish) before_publish(r);
    std::lock_guard lock(mutex_);
    results.push_back(r);
    if (r.has_frame) ++frames;
    changed_.notify_all();
  }
  void publishStatus(const PipelineStatus& s) override {
    std::lock_guard lock(mutex_);
    statuses.push_back(s);
    changed_.notify_all();
  }
  /// Blocks until a status satisfying `wanted` was published; returns a copy of it.
  PipelineStatus waitForStatus(const std::function<bool(const PipelineStatus&)>& wanted) {
    std::unique_lock lock(mutex_);
    const PipelineStatus* found = nullptr;
    changed_.wait(lock, [&] {
      for (const PipelineStatus& s : statuses)
        if (wanted(s)) found = &s;
      return found != nullptr;
    });
    return *found;
  }
  void waitForFrames(int n) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return frames >= n; });
  }
  /// Like waitForFrames() but gives up after `limit` (a guard against a hang, not a timing). True if seen.
  bool waitForFramesFor(int n, std::chrono::seconds limit) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, limit, [&] { return frames >= n; });
  }
  std::function<void(const FrameResult&)> before_publish;  ///< e.g. a slow consumer
  std::vector<FrameResult> results;
  std::vector<PipelineStatus> statuses;
  int frames = 0;

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
};

}  // namespace toposlam::test
