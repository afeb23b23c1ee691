// The video-file frame source (`video:FILE`), over OpenCV's videoio. Lives in its own loadable module
// (toposlam-source-video.so, see video_module.cpp): OpenCV's videoio pulls in about 100 shared
// libraries (FFmpeg, GStreamer, ...), which every program would otherwise load and relocate at start-up
// even when it never opens a video. Private to platform/video; apps reach it through openFrameSource.
// Not thread-safe: one consumer calls next(); interrupt() from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include <opencv2/videoio.hpp>

#include "toposlam/pipeline/frame_source.hpp"

namespace toposlam {

class VideoFileSource : public FrameSource {
 public:
  /// Throws FrameSourceError when the file cannot be opened. timestamp_rate_hz > 0 overrides the
  /// container's timestamps with frame index / rate.
  explicit VideoFileSource(const std::string& path, double timestamp_rate_hz = 0.0);
  std::string describe() const override;
  std::optional<Frame> next() override;
  void interrupt() override { interrupted_.store(true); }
  std::int64_t skippedFrames() const override { return skipped_; }
  /// Frames of an unexpected pixel type (all of them WrongFormat).
  SkippedFrames skippedByReason() const override {
    SkippedFrames skipped;
    skipped[SkipReason::WrongFormat] = skipped_;
    return skipped;
  }
  std::int64_t frameCountHint() const override { return frame_count_; }
  FrameSourceState state() const override { return FrameSourceState::of(SourceKind::VideoFile); }

 private:
  std::string path_;
  cv::VideoCapture capture_;
  double rate_hz_;
  double container_fps_ = 0;
  std::int64_t frame_count_ = -1;
  std::int64_t next_index_ = 0;
  std::int64_t skipped_ = 0;
  std::atomic<bool> interrupted_{false};
};

}  // namespace toposlam
