// FrameRecorder: writes the frames a source delivers into a folder an `images:` source plays back —
// 000000.jpg, 000001.jpg, ... and timestamps.csv ("name,time_s", the frames' own timestamps, written
// line by line so a recording cut short still plays). `images:DIR?rate=recorded` replays it at the
// recorded pace (io/source_factory.hpp). Bounded by size: once the frames written reach max_bytes the
// recorder refuses further frames (record() returns false) and says how many it kept.
//
// Used by `toposlam capture URI --record DIR`. Not thread-safe: one thread records.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "toposlam/pipeline/frame_source.hpp"

namespace toposlam {

struct FrameRecorderConfig {
  std::string format = "jpg";             ///< "jpg" (quality below) or "png" (lossless, about 5x larger)
  int jpeg_quality = 95;                  ///< 1 .. 100
  std::uint64_t max_bytes = 1ull << 30;   ///< frames stop being recorded once this much was written
};

class FrameRecorder {
 public:
  /// Creates `folder` (and parents). Throws FrameSourceError naming the folder when it cannot, when it
  /// already holds image files or a timestamps.csv (never mixes two recordings), or on a bad config.
  FrameRecorder(std::filesystem::path folder, FrameRecorderConfig config);

  /// Writes the frame and its timestamp line. False (nothing written) once the size bound is reached.
  /// Throws FrameSourceError naming the file on a write error (a full disk).
  bool record(const Frame& frame);
  /// Flushes timestamps.csv; throws FrameSourceError naming it on a write error.
  void finish();

  std::int64_t frames() const { return frames_; }
  std::uint64_t bytes() const { return bytes_; }
  bool full() const { return full_; }
  const std::filesystem::path& folder() const { return folder_; }

 private:
  std::filesystem::path folder_;
  FrameRecorderConfig config_;
  std::ofstream timestamps_;
  std::vector<unsigned char> encoded_;
  std::int64_t frames_ = 0;
  std::uint64_t bytes_ = 0;
  bool full_ = false;
};

}  // namespace toposlam
