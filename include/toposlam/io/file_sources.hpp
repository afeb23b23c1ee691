// Frame sources over files: an image folder or glob, played in natural order. (Video files: platform/video,
// a module loaded on first use.)
// Bad files (unreadable, truncated, undecodable) are skipped, counted and logged; the stream goes on.
// Not thread-safe: one consumer calls next(); interrupt() (ends the stream early) from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "toposlam/core/warning_throttle.hpp"
#include "toposlam/io/image_file.hpp"
#include "toposlam/pipeline/frame_source.hpp"

namespace toposlam {

/// True for .png, .jpg, .jpeg, .bmp (case-insensitive).
bool isImageFileName(const std::string& name);
/// True for .mp4, .avi, .mkv, .mov, .webm, .m4v, .mpg, .mpeg, .wmv (case-insensitive).
bool isVideoFileName(const std::string& name);
/// The image files of a folder, or the matches of a glob, or a single image file, in natural order.
/// Throws FrameSourceError when nothing matches.
std::vector<std::string> listImageFiles(const std::string& path_or_glob);
/// imageBytesLookComplete(): image_file.hpp.

class ImageFilesSource : public FrameSource {
 public:
  /// timestamps are file index / timestamp_rate_hz (the bundled samples are ~1 Hz keyframes). A file whose
  /// header claims more than max_pixels pixels is skipped undecoded (image_file.hpp). rate_given = false:
  /// the rate is an assumption, and describe() says so; then a timestamps.csv (name,time_s) beside the
  /// files, as `toposlam sim` writes, gives each frame its own time.
  ImageFilesSource(const std::string& path_or_glob, double timestamp_rate_hz = 1.0,
                   std::int64_t max_pixels = kDefaultMaxImagePixels, bool rate_given = true);
  std::string describe() const override;
  std::optional<Frame> next() override;
  void interrupt() override { interrupted_.store(true); }
  std::int64_t skippedFrames() const override { return skipped_.total(); }
  /// Unreadable, truncated, corrupt or over the caps (ImageReadError::Kind).
  SkippedFrames skippedByReason() const override { return skipped_; }
  std::int64_t frameCountHint() const override { return static_cast<std::int64_t>(files_.size()); }
  FrameSourceState state() const override { return FrameSourceState::of(SourceKind::ImageFiles); }
  /// The file name (without its folder) of file `sequence`; "" out of range.
  std::string frameName(std::int64_t sequence) const override;
  /// The file `last_sequence` when it has that name, else the first file of that name (files were added or
  /// removed before it); nullopt when no file has it. Logs what is skipped.
  std::optional<std::int64_t> continueAfter(std::int64_t last_sequence, const std::string& last_name) override;
  const std::vector<std::string>& files() const { return files_; }

 private:
  std::string origin_;
  std::vector<std::string> files_;
  double rate_hz_;
  std::int64_t max_pixels_;
  bool rate_given_ = true;
  std::vector<double> times_;    ///< per file, from timestamps.csv beside the files; empty = index / rate
  std::string timestamps_file_;  ///< that file, for describe()
  std::size_t next_index_ = 0;
  SkippedFrames skipped_;
  // One warning per bad file for the first few, then summaries (a folder of 5,000 bad files gave 4,900
  // lines); the last summary when the files run out.
  WarningThrottle skip_warnings_;
  std::atomic<bool> interrupted_{false};
};

}  // namespace toposlam
