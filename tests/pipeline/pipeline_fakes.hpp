// Fake stages for pipeline tests: a counting frame source, a fingerprint stage with hooks, a segmentation
// that closes a place every N frames, and a topology filter whose step costs a fixed number of slices of
// manual-clock time (so "spread over frames" is exact and needs no wall clock).
#pragma once

#include <atomic>
#include <condition_variable>
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
  std::optional<Frame> next() override {
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
  std::atomic<int> released{0};

 private:
  std::int64_t count_;
  std::int64_t produced_ = 0;
};

class FakeFingerprint final : public FingerprintStage {
 public:
  Fingerprint process(const cv::Mat& image) override {
    const int value = image.at<cv::Vec3b>(0, 0)[0];
    if (on_process) on_process(value);
    if (throw_when && throw_when(value)) throw std::invalid_argument("unreadable frame");
    Fingerprint f;
    f.image_width = image.cols;
    f.image_height = image.rows;
    return f;
  }
  std::function<void(int)> on_process;   ///< argument: the frame's pixel value (sequence % 256)
  std::function<bool(int)> throw_when;
};

class FakeSegmentation final : public SegmentationStage {
 public:
  explicit FakeSegmentation(int period) : period_(period) {}
  SegmentationStep process(std::int64_t sequence, std::shared_ptr<const Fingerprint> fingerprint,
                           const cv::Mat& thumbnail) override {
    if (throw_at >= 0 && sequence == throw_at) throw std::runtime_error("boom");
    SegmentationStep step;
    step.lambda2 = static_cast<double>(sequence);
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
  int closed = 0;
  std::int64_t throw_at = -1;

 private:
  int period_;
};

class FakeTopology final : public TopologyStage {
 public:
  FakeTopology(ManualClock& clock, int slices_per_step, double slice_s)
      : clock_(clock), slices_per_step_(slices_per_step), slice_s_(slice_s) {}
  void enqueuePlace(const ClosedPlace& place) override { queue_.push_back(place.place); }
  std::optional<PlaceAssignment> advance(double budget_s) override {
    const double deadline = clock_.now() + budget_s;
    do {
      if (queue_.empty()) return std::nullopt;
      clock_.advance(slice_s_);  // one slice of work costs slice_s of (manual) time
      if (++done_slices_ == slices_per_step_) {
        done_slices_ = 0;
        const int place = queue_.front();
        queue_.erase(queue_.begin());
        ++revision_;
        estimate_.place = place;
        estimate_.node = place % 3;  // a loop of three rooms
        estimate_.is_new = place < 3;
        estimate_.probability = 0.9;
        estimate_.map_revision = revision_;
        PlaceAssignment a{place, estimate_.node, estimate_.is_new, 0.9};
        return a;
      }
    } while (clock_.now() < deadline);
    return std::nullopt;
  }
  bool idle() const override { return queue_.empty(); }
  PlaceEstimate estimate() const override { return estimate_; }
  TopologySnapshot topology() const override {
    TopologySnapshot t;
    t.map_revision = revision_;
    return t;
  }
  void saveMap(const std::string& path) const override {
    saves.push_back(path);
    saved_while_idle.push_back(idle());
    saved_at_revision.push_back(revision_);
  }
  mutable std::vector<std::string> saves;
  mutable std::vector<bool> saved_while_idle;
  mutable std::vector<std::int64_t> saved_at_revision;

 private:
  ManualClock& clock_;
  int slices_per_step_;
  double slice_s_;
  std::vector<int> queue_;
  int done_slices_ = 0;
  std::int64_t revision_ = 0;
  PlaceEstimate estimate_;
};

/// Records everything; can wake a waiting test after N frames.
class RecordingSink final : public PipelineSink {
 public:
  void publish(const FrameResult& r) override {
    std::lock_guard lock(mutex_);
    results.push_back(r);
    if (r.has_frame) ++frames;
    changed_.notify_all();
  }
  void publishStatus(const PipelineStatus& s) override {
    std::lock_guard lock(mutex_);
    statuses.push_back(s);
  }
  void waitForFrames(int n) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return frames >= n; });
  }
  std::vector<FrameResult> results;
  std::vector<PipelineStatus> statuses;
  int frames = 0;

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
};

}  // namespace toposlam::test
