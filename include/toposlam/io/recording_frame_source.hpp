// RecordingFrameSource: records the frames a live pipeline processes without ever holding it up. It wraps
// the pipeline's FrameSource and passes every frame through unchanged; on the way it copies the frame's
// pixels into a bounded queue (drop-oldest, counted: a slow disk loses recorded frames, never pipeline
// frames), and a writer thread the owner runs (runWriter(), `tsl-record` in toposlamd's thread table) encodes
// and writes them with FrameRecorder, in the folder format `toposlam capture --record` writes, so
// `images:DIR?rate=recorded` replays it (io/frame_recorder.hpp).
//
// It stops recording, and says so once in the log, when the size bound is reached (FrameRecorderConfig::
// max_bytes) or a write fails (a full disk): the frames written so far stay a valid recording, and the
// pipeline goes on. status() tells which.
//
// Thread-safety: the FrameSource calls come from the pipeline's capture thread (interrupt() and state() from
// any thread); runWriter() from one writer thread; closeWriter() and status() from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "toposlam/io/frame_recorder.hpp"
#include "toposlam/pipeline/bounded_queue.hpp"
#include "toposlam/pipeline/frame_source.hpp"

namespace toposlam {

enum class RecordingState : int {
  Recording = 0,  ///< frames are being written
  Full = 1,       ///< the size bound was reached: recording stopped, the pipeline goes on
  Failed = 2,     ///< a write failed (a full disk, a removed folder): recording stopped, the pipeline goes on
  Finished = 3,   ///< the writer ended (end of stream or stop) with every queued frame written
};
/// "recording", "full", "failed", "finished".
const char* toString(RecordingState state);

/// A snapshot of the recording (counts since start).
struct RecordingStatus {
  RecordingState state = RecordingState::Recording;
  std::int64_t offered = 0;   ///< frames the source delivered while recording
  std::int64_t written = 0;   ///< frames written to the folder
  std::int64_t dropped = 0;   ///< frames the writer did not keep up with (dropped oldest from its queue)
  std::uint64_t bytes = 0;    ///< bytes of the frames written
  std::string folder;
  std::string problem;        ///< why recording stopped (Full, Failed); empty otherwise
};

/// The folder of one recording under `parent`: "<parent>/<UTC time, 20261202T111500Z>", with "-2", "-3", ...
/// appended when that name exists already (two starts within a second).
std::filesystem::path newRecordingFolder(const std::filesystem::path& parent, std::int64_t unix_seconds);

/// Bytes of the regular files under `folder`, recursively (0 when it does not exist); for a bound over all
/// recordings kept there.
std::uint64_t bytesUnder(const std::filesystem::path& folder);

class RecordingFrameSource final : public FrameSource {
 public:
  /// `recorder` writes into its (already created, empty) folder; `queue_frames` (>= 1) frames may wait for
  /// the writer.
  RecordingFrameSource(std::unique_ptr<FrameSource> inner, std::unique_ptr<FrameRecorder> recorder,
                       int queue_frames);
  ~RecordingFrameSource() override;

  std::string describe() const override;
  std::optional<Frame> next() override;
  SourceWait nextFor(std::chrono::milliseconds timeout, Frame& out) override;
  void interrupt() override { inner_->interrupt(); }
  FrameSourceState state() const override { return inner_->state(); }
  bool realTime() const override { return inner_->realTime(); }
  std::int64_t skippedFrames() const override { return inner_->skippedFrames(); }
  SkippedFrames skippedByReason() const override { return inner_->skippedByReason(); }
  std::int64_t frameCountHint() const override { return inner_->frameCountHint(); }
  std::string frameName(std::int64_t sequence) const override { return inner_->frameName(sequence); }
  std::optional<std::int64_t> continueAfter(std::int64_t last_sequence, const std::string& last_name) override {
    return inner_->continueAfter(last_sequence, last_name);
  }

  /// The writer thread's body: writes queued frames until closeWriter() and the queue is drained, or until
  /// recording stops (size bound, write error; logged once). Never throws.
  void runWriter();
  /// No more frames: runWriter() writes what is queued and returns. Idempotent.
  void closeWriter();
  RecordingStatus status() const;

 private:
  struct QueuedFrame {
    cv::Mat image;
    std::int64_t sequence = 0;
    double timestamp_s = 0.0;
  };
  void offer(const Frame& frame);
  void stopRecording(RecordingState state, const std::string& problem);
  cv::Mat takeSpare();
  void giveBack(cv::Mat image);

  std::unique_ptr<FrameSource> inner_;
  std::unique_ptr<FrameRecorder> recorder_;  ///< the writer thread's only
  BoundedQueue<QueuedFrame> queue_;
  std::atomic<int> state_{static_cast<int>(RecordingState::Recording)};
  std::atomic<std::int64_t> offered_{0};
  std::atomic<std::int64_t> written_{0};
  std::atomic<std::uint64_t> bytes_{0};
  const std::string folder_;
  mutable std::mutex mutex_;          ///< guards problem_ and spare_
  std::string problem_;
  std::vector<cv::Mat> spare_;        ///< pixel buffers the writer is done with, reused by the next copies
};

}  // namespace toposlam
