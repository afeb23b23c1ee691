// Shared pieces of `toposlam segment` and `toposlam map` (see offline_run_io.hpp).
#include "offline_run_io.hpp"

#include <cstdio>
#include <stdexcept>
#include <vector>

#include "toposlam/io/image_codec.hpp"

#include "toposlam/io/source_factory.hpp"

namespace toposlam::cli {

std::unique_ptr<FrameSource> openSource(const std::string& uri) { return openFrameSource(uri); }

OutputFile openOutput(const std::filesystem::path& path) { return OutputFile(path); }

void writeImageFile(const std::filesystem::path& path, const cv::Mat& image) {
  const std::optional<ImageFormat> format = imageFormatOfPath(path.string());
  if (!format) throw OutputFileError(path.string() + ": cannot encode the image (name it .png, .jpg or .bmp)");
  std::vector<unsigned char> encoded;
  try {
    encodeImage(image, *format, encoded);
  } catch (const ImageCodecError& e) {
    throw OutputFileError(path.string() + ": cannot encode the image: " + e.what());
  }
  OutputFile out(path);
  out.write(reinterpret_cast<const char*>(encoded.data()), static_cast<std::streamsize>(encoded.size()));
  out.commit();
}

void addSegmentationOptions(CLI::App& command, ConfigOptions& options) {
  // --window N alone is a window of N frames (window_s 0); --window-s, given too, comes after it and wins.
  addKeyAlias(command, options, "--window", {"segmentation.window_s=0", "segmentation.window"}, {},
              "= --set segmentation.window_s=0 --set segmentation.window=N: a window of N frames (with --window-s: "
              "the most frames it may hold)");
  addKeyAlias(command, options, "--window-s", "segmentation.window_s");
  addKeyAlias(command, options, "--min-window-frames", "segmentation.min_window_frames");
  addKeyAlias(command, options, "--gamma", "segmentation.valley.gamma");
  addKeyAlias(command, options, "--delta", "segmentation.valley.delta");
  addKeyAlias(command, options, "--similarity-floor", "segmentation.similarity_floor");
  addKeyAlias(command, options, "--min-keypoints", "segmentation.min_keypoints");
  addKeyAlias(command, options, "--cut", "segmentation.cut_placement");
  addKeyAlias(command, options, "--doorway-shift-s", "segmentation.doorway_shift_s");
  addKeyAlias(command, options, "--doorway-borders", "segmentation.doorway_borders");
  addKeyAlias(command, options, "--representative", "segmentation.representative");
  addKeyAlias(command, options, "--representative-interval-s", "segmentation.representative_interval_s");
  addKeyAlias(command, options, "--place-samples", "segmentation.place_samples");
  addKeyAlias(command, options, "--keypoints", "fingerprint.keypoints.backend");
}

std::string timelineSummary(const FrameTimeline& timeline, const std::string& command) {
  char text[320];
  std::snprintf(text, sizeof text,
                "%s: the source's clock went back %lld time(s) (the last by %.3f s); each such frame was placed one "
                "frame interval after the one before and the frames after it kept their spacing (frames.csv's time)",
                command.c_str(), static_cast<long long>(timeline.stepsBack()), timeline.lastStepBackS());
  return text;
}

}  // namespace toposlam::cli
