// Shared pieces of `toposlam segment` and `toposlam map` (see offline_run_io.hpp).
#include "offline_run_io.hpp"
#include "config_key_options.hpp"

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

namespace {
enum SegmentationKey { kWindowS, kWindow, kMinWindowFrames, kGamma, kDelta, kFloor, kMinKeypoints, kCut, kDoorwayShift, kDoorwayBorders, kRepresentative, kRepresentativeInterval, kPlaceSamples };
}  // namespace

void addSegmentationOptions(CLI::App& command, SegmentationOptions& options) {
  FiedlerSegmenterConfig& c = options.config;
  const FiedlerSegmenterConfig d = methodPreset("default").segmentation;
  c = d;
  options.cut = toString(d.cut_placement);
  options.representative = toString(d.representative);
  auto& given = options.given;
  command.add_option("--preset", options.preset, "Method preset: default (measured on real frames) or thesis")
      ->capture_default_str();
  given.emplace_back(command.add_option("--window-s", c.window_s,
                                        "Segmentation: sliding window in seconds, from the frames' timestamps "
                                        "(0 = --window frames)")
                         ->capture_default_str()
                         ->check(keyRange("segmentation.window_s")),
                     kWindowS);
  given.emplace_back(command.add_option("--window", c.window,
                                        "Segmentation: window in frames with --window-s 0, else the most frames "
                                        "it may hold")
                         ->capture_default_str()
                         ->check(keyRange("segmentation.window")),
                     kWindow);
  given.emplace_back(command.add_option("--min-window-frames", c.min_window_frames,
                                        "Segmentation: fewest frames a window in seconds keeps")
                         ->capture_default_str()
                         ->check(keyRange("segmentation.min_window_frames")),
                     kMinWindowFrames);
  given.emplace_back(command.add_option("--gamma", c.valley.gamma, "Segmentation: minimum lambda2 of a peak, [0, n/(n-1)]")
                         ->capture_default_str(),
                     kGamma);
  given.emplace_back(command.add_option("--delta", c.valley.delta,
                                        "Segmentation: minimum lambda2 swing between peak and valley, [0, gamma]")
                         ->capture_default_str(),
                     kDelta);
  given.emplace_back(command.add_option("--similarity-floor", c.similarity_floor,
                                        "Segmentation: subtracted from every similarity before the affinity, [0, 1)")
                         ->capture_default_str(),
                     kFloor);
  given.emplace_back(command.add_option("--min-keypoints", c.min_keypoints,
                                        "Segmentation: drop places whose representative has fewer keypoints")
                         ->capture_default_str(),
                     kMinKeypoints);
  given.emplace_back(command.add_option("--cut", options.cut,
                                        "Segmentation: where a place ends: window-split (best split of the valley's "
                                        "window) or valley-frame")
                         ->capture_default_str()
                         ->check(CLI::IsMember({"window-split", "valley-frame"})),
                     kCut);
  given.emplace_back(command.add_option("--doorway-shift-s", c.doorway_shift_s,
                                        "Segmentation: move a border to the doorway passage nearest it (seen in the "
                                        "vertical edges) when one is at most this many seconds away (0 = off)")
                         ->capture_default_str()
                         ->check(keyRange("segmentation.doorway_shift_s")),
                     kDoorwayShift);
  given.emplace_back(command.add_option("--doorway-borders", c.doorway_borders,
                                        "Segmentation: with --doorway-shift-s > 0, a doorway passage makes a border "
                                        "of its own and a second border for one doorway is dropped (true/false)")
                         ->capture_default_str(),
                     kDoorwayBorders);
  given.emplace_back(command.add_option("--representative", options.representative,
                                        "Segmentation: a place's representative: window-degree (the thesis) or "
                                        "place-medoid (the sampled frame most like the place's others)")
                         ->capture_default_str()
                         ->check(CLI::IsMember({"window-degree", "place-medoid"})),
                     kRepresentative);
  given.emplace_back(command.add_option("--representative-interval-s", c.representative_interval_s,
                                        "Segmentation (place-medoid): sample the place's frames at most this often")
                         ->capture_default_str()
                         ->check(keyRange("segmentation.representative_interval_s")),
                     kRepresentativeInterval);
  given.emplace_back(command.add_option("--place-samples", c.place_samples,
                                        "Segmentation: other frames of a place compared with the stored places "
                                        "besides its representative (0 = the representative alone, the thesis)")
                         ->capture_default_str()
                         ->check(keyRange("segmentation.place_samples")),
                     kPlaceSamples);
}

MethodPreset presetOf(const SegmentationOptions& options, const std::string& command) {
  try {
    return methodPreset(options.preset);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(command + ": --preset: " + e.what());
  }
}

FiedlerSegmenterConfig segmenterConfig(const SegmentationOptions& options, const std::string& command) {
  FiedlerSegmenterConfig config = presetOf(options, command).segmentation;
  const FiedlerSegmenterConfig& o = options.config;
  for (const auto& [option, key] : options.given) {
    if (option->count() == 0) continue;
    switch (key) {
      case kWindowS: config.window_s = o.window_s; break;
      case kWindow: config.window = o.window; break;
      case kMinWindowFrames: config.min_window_frames = o.min_window_frames; break;
      case kGamma: config.valley.gamma = o.valley.gamma; break;
      case kDelta: config.valley.delta = o.valley.delta; break;
      case kFloor: config.similarity_floor = o.similarity_floor; break;
      case kMinKeypoints: config.min_keypoints = o.min_keypoints; break;
      case kCut: config.cut_placement = parseCutPlacement(options.cut); break;
      case kDoorwayShift: config.doorway_shift_s = o.doorway_shift_s; break;
      case kDoorwayBorders: config.doorway_borders = o.doorway_borders; break;
      case kRepresentative: config.representative = parseRepresentativeChoice(options.representative); break;
      case kRepresentativeInterval: config.representative_interval_s = o.representative_interval_s; break;
      case kPlaceSamples: config.place_samples = o.place_samples; break;
    }
  }
  // --window alone asks for a window of that many frames (the time window is for --window-s).
  bool window_given = false, window_s_given = false;
  for (const auto& [option, key] : options.given) {
    window_given = window_given || (key == kWindow && option->count() > 0);
    window_s_given = window_s_given || (key == kWindowS && option->count() > 0);
  }
  if (window_given && !window_s_given) config.window_s = 0.0;
  // A frame window smaller than the time window's lower bound: the bound follows it.
  if (config.min_window_frames > config.window) config.min_window_frames = config.window;
  if (const std::string problem = config.validate(); !problem.empty()) {
    throw std::invalid_argument(command + ": " + problem);
  }
  return config;
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
