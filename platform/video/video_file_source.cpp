// The video-file frame source: see video_file_source.hpp.
#include "video_file_source.hpp"

#include <filesystem>

#include <spdlog/spdlog.h>

namespace toposlam {

VideoFileSource::VideoFileSource(const std::string& path, double timestamp_rate_hz)
    : path_(path), rate_hz_(timestamp_rate_hz) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw FrameSourceError("video: no such file '" + path + "'");
  if (!capture_.open(path) || !capture_.isOpened()) {
    throw FrameSourceError("video: cannot open '" + path + "' (unsupported container or codec?)");
  }
  container_fps_ = capture_.get(cv::CAP_PROP_FPS);
  const double count = capture_.get(cv::CAP_PROP_FRAME_COUNT);
  frame_count_ = count > 0 ? static_cast<std::int64_t>(count) : -1;
}

std::string VideoFileSource::describe() const {
  return "video:" + path_ + " (" + (frame_count_ >= 0 ? std::to_string(frame_count_) : std::string("?")) +
         " frames)";
}

std::optional<Frame> VideoFileSource::next() {
  for (;;) {
    if (interrupted_.load()) return std::nullopt;
    cv::Mat image;
    if (!capture_.read(image) || image.empty()) return std::nullopt;
    const std::int64_t index = next_index_++;
    if (image.type() != CV_8UC3) {
      ++skipped_;
      spdlog::warn("video: skipping frame {} of '{}': unexpected pixel type", index, path_);
      continue;
    }
    Frame frame;
    frame.image = image;
    frame.sequence = index;
    if (rate_hz_ > 0) {
      frame.timestamp_s = static_cast<double>(index) / rate_hz_;
    } else if (container_fps_ > 0) {
      frame.timestamp_s = static_cast<double>(index) / container_fps_;
    } else {
      frame.timestamp_s = capture_.get(cv::CAP_PROP_POS_MSEC) / 1000.0;
    }
    return frame;
  }
}

}  // namespace toposlam
