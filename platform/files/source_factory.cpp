// The frame-source registry and factory (source_factory.hpp), with the built-in schemes images:,
// video:, libcamera: and sim:, plain paths, and the real-time `rate` wrapper.
#include "toposlam/io/source_factory.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <mutex>
#include <condition_variable>

#include "toposlam/core/frame_timeline.hpp"
#include "toposlam/io/file_sources.hpp"
#include "toposlam/io/image_file.hpp"
#include "toposlam/io/sim_source.hpp"
#include "source_modules.hpp"

namespace toposlam {

namespace {

struct SchemeEntry {
  FrameSourceOpener opener;
  std::string usage;
  FrameSourceChecker checker;  ///< may be empty: only the scheme is known to be right
};

// Holds the next frame until it is due; the wait is bounded (nextFor) and ends early on interrupt(). Due:
// frame k at k / rate_hz after the first, or with rate_hz 0 at its timestamp's offset from the first's on
// a FrameTimeline: a timestamp that goes back is due one typical interval after the frame before (not all
// at once until the recording catches up with its own clock); a jump forward is waited for, as recorded.
class RateLimitedSource : public FrameSource {
 public:
  RateLimitedSource(std::unique_ptr<FrameSource> inner, double rate_hz) : inner_(std::move(inner)), rate_hz_(rate_hz) {}
  std::string describe() const override {
    return inner_->describe() +
           (rate_hz_ > 0 ? " at " + std::to_string(rate_hz_) + " Hz real time" : " at the recorded rate (frame timestamps)");
  }
  std::optional<Frame> next() override {
    for (;;) {
      Frame frame;
      const SourceWait wait = nextFor(std::chrono::hours(1), frame);
      if (wait == SourceWait::Frame) return frame;
      if (wait == SourceWait::End) return std::nullopt;
    }
  }
  SourceWait nextFor(std::chrono::milliseconds timeout, Frame& out) override {
    if (!pending_) {
      Frame frame;
      const SourceWait wait = inner_->nextFor(timeout, frame);
      if (wait != SourceWait::Frame) return wait;
      const auto now = std::chrono::steady_clock::now();
      const double placed_s = rate_hz_ > 0 ? 0.0 : timeline_.place(frame.timestamp_s);
      if (delivered_ == 0) {
        start_ = now;
        first_timestamp_s_ = placed_s;
      }
      const double offset_s = rate_hz_ > 0 ? static_cast<double>(delivered_) / rate_hz_
                                           : std::max(0.0, placed_s - first_timestamp_s_);
      due_ = start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(offset_s));
      pending_ = std::move(frame);
    }
    {
      std::unique_lock lock(mutex_);
      const auto until = std::min(due_, std::chrono::steady_clock::now() + timeout);
      woken_.wait_until(lock, until, [this] { return interrupted_; });
      if (interrupted_) return SourceWait::End;
    }
    if (std::chrono::steady_clock::now() < due_) return SourceWait::Timeout;
    ++delivered_;
    out = std::move(*pending_);
    pending_.reset();
    return SourceWait::Frame;
  }
  void interrupt() override {
    {
      std::lock_guard lock(mutex_);
      interrupted_ = true;
    }
    woken_.notify_all();
    inner_->interrupt();
  }
  FrameSourceState state() const override { return inner_->state(); }
  bool realTime() const override { return true; }  // frames come when due, not when asked for
  std::int64_t skippedFrames() const override { return inner_->skippedFrames(); }
  SkippedFrames skippedByReason() const override { return inner_->skippedByReason(); }
  std::int64_t frameCountHint() const override { return inner_->frameCountHint(); }
  std::string frameName(std::int64_t sequence) const override { return inner_->frameName(sequence); }
  std::optional<std::int64_t> continueAfter(std::int64_t last_sequence, const std::string& last_name) override {
    return inner_->continueAfter(last_sequence, last_name);
  }

 private:
  std::unique_ptr<FrameSource> inner_;
  double rate_hz_;  ///< 0: the recorded rate (frame timestamps)
  double first_timestamp_s_ = 0.0;  ///< on timeline_
  FrameTimeline timeline_;          ///< the recorded timestamps with their steps back cut out
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point due_;
  std::optional<Frame> pending_;  ///< taken from the inner source, not yet due
  std::int64_t delivered_ = 0;
  std::mutex mutex_;
  std::condition_variable woken_;
  bool interrupted_ = false;
};

/// An images: URI's settings, checked.
struct ImagesParameters {
  double hz = 1.0;
  std::int64_t max_pixels = kDefaultMaxImagePixels;
  bool hz_given = false;
};

ImagesParameters imagesParameters(const SourceUri& uri) {
  uri.requireOnly({"fps", "max_pixels"});
  if (uri.path.empty()) throw FrameSourceError("source '" + uri.text + "': images: needs a folder, file or glob");
  // Frame timestamps (the segmentation window is in seconds): ?fps=HZ, else the real-time ?rate=HZ,
  // else 1 Hz (the bundled keyframes' rate), said in describe() so a user sees the assumption.
  // rate=recorded takes the times from timestamps.csv beside the frames.
  const bool recorded = playsAtRecordedRate(uri);
  ImagesParameters p;
  p.hz_given = uri.has("fps") || (uri.has("rate") && !recorded);
  p.hz = uri.has("fps") ? uri.getDouble("fps", 1.0, 1e-3, 1e4)
         : recorded     ? 1.0
                        : uri.getDouble("rate", 1.0, 1e-3, 1e4);
  p.max_pixels = uri.getInt("max_pixels", kDefaultMaxImagePixels, 1, 1LL << 32);
  return p;
}

std::unique_ptr<FrameSource> openImages(const SourceUri& uri) {
  const ImagesParameters p = imagesParameters(uri);
  return std::make_unique<ImageFilesSource>(uri.path, p.hz, p.max_pixels, p.hz_given);
}

/// A video: URI's rate (0: as fast as asked, or the recorded rate), checked.
double videoRate(const SourceUri& uri) {
  uri.requireOnly({});
  if (uri.path.empty()) throw FrameSourceError("source '" + uri.text + "': video: needs a file");
  return playsAtRecordedRate(uri) ? 0.0 : uri.getDouble("rate", 0.0, 1e-3, 1e4);
}

// video: lives in a module loaded on first use (source_modules.hpp; platform/video).
std::unique_ptr<FrameSource> openVideo(const SourceUri& uri) {
  const double rate = videoRate(uri);
  using Open = FrameSource* (*)(const char*, double, std::string*);
  const auto open = reinterpret_cast<Open>(sourceModuleSymbol("video", "toposlam_source_video_open_v2"));
  std::string error;
  std::unique_ptr<FrameSource> source(open(uri.path.c_str(), rate, &error));
  if (!source) throw FrameSourceError(error);
  return source;
}

// libcamera: too (platform/libcamera): libcamera and the ~30 libraries behind it load only for a camera.
std::unique_ptr<FrameSource> openLibcamera(const SourceUri& uri) {
  using Open = FrameSource* (*)(const char*, std::string*);
  const auto open = reinterpret_cast<Open>(sourceModuleSymbol("libcamera", "toposlam_source_libcamera_open_v2"));
  std::string error;
  std::unique_ptr<FrameSource> source(open(uri.text.c_str(), &error));
  if (!source) throw FrameSourceError(error);
  return source;
}

std::unique_ptr<FrameSource> openSim(const SourceUri& uri) { return std::make_unique<SimFrameSource>(simConfigFromUri(uri)); }

struct Registry {
  std::mutex mutex;
  std::map<std::string, SchemeEntry> schemes;
  Registry() {
    schemes["images"] = {openImages, "images:FOLDER_OR_GLOB[?fps=HZ&rate=HZ|recorded&max_pixels=N]",
                         [](const SourceUri& uri) { (void)imagesParameters(uri); }};
    schemes["video"] = {openVideo, "video:FILE[?rate=HZ|recorded]", [](const SourceUri& uri) { (void)videoRate(uri); }};
    schemes["libcamera"] = {openLibcamera, "libcamera:ID?size=WxH&buffers=N (empty ID: the first camera)", {}};
    schemes["sim"] = {openSim,
                      "sim:WORLD?route=R&fps=F&size=WxH&seed=S[&speed=&fov=&light=day|night|warm|cool&noise=&people=&"
                      "pitch=&moved=0|1&rate=HZ]",
                      [](const SourceUri& uri) { (void)simConfigFromUri(uri); }};
  }
};

Registry& registry() {
  static Registry instance;
  return instance;
}

std::string schemeList() {
  std::string list;
  for (const auto& [scheme, usage] : registeredFrameSourceSchemes()) list += "\n  " + usage;
  return list;
}

}  // namespace

void registerFrameSourceScheme(const std::string& scheme, FrameSourceOpener opener, const std::string& usage,
                               FrameSourceChecker checker) {
  const bool valid = !scheme.empty() && std::all_of(scheme.begin(), scheme.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
  if (!valid || !opener) throw FrameSourceError("registerFrameSourceScheme: bad scheme '" + scheme + "' or no opener");
  Registry& entries = registry();
  const std::lock_guard lock(entries.mutex);
  entries.schemes[scheme] = {std::move(opener), usage, std::move(checker)};
}

std::vector<std::pair<std::string, std::string>> registeredFrameSourceSchemes() {
  Registry& entries = registry();
  const std::lock_guard lock(entries.mutex);
  std::vector<std::pair<std::string, std::string>> result;
  for (const auto& [scheme, entry] : entries.schemes) result.emplace_back(scheme, entry.usage);
  return result;
}

std::unique_ptr<FrameSource> openFrameSource(const std::string& text) {
  SourceUri uri = parseSourceUri(text);
  if (uri.scheme.empty()) {
    std::error_code error;
    if (std::filesystem::is_directory(uri.path, error)) {
      uri.scheme = "images";
    } else if (std::filesystem::is_regular_file(uri.path, error) && isVideoFileName(uri.path)) {
      uri.scheme = "video";
    } else if (isImageFileName(uri.path) || uri.path.find_first_of("*?[") != std::string::npos) {
      uri.scheme = "images";
    } else {
      throw FrameSourceError("source '" + text +
                             "': not a folder, a video file or an image file/glob, and no scheme given; use one of:" +
                             schemeList());
    }
  }
  FrameSourceOpener opener;
  {
    Registry& entries = registry();
    const std::lock_guard lock(entries.mutex);
    const auto found = entries.schemes.find(uri.scheme);
    if (found != entries.schemes.end()) opener = found->second.opener;
  }
  if (!opener) throw FrameSourceError("source '" + text + "': unknown scheme '" + uri.scheme + ":'; use one of:" + schemeList());
  const bool recorded = playsAtRecordedRate(uri);
  const double rate = recorded ? 0.0 : uri.getDouble("rate", 0.0, 1e-3, 1e4);
  std::unique_ptr<FrameSource> source = opener(uri);
  if (recorded) source = makeRecordedRateSource(std::move(source));
  if (rate > 0) source = makeRateLimitedSource(std::move(source), rate);
  return source;
}

void checkFrameSourceUri(const std::string& text) {
  const SourceUri uri = parseSourceUri(text);
  if (uri.scheme.empty()) return;
  FrameSourceChecker checker;
  bool known = false;
  {
    Registry& entries = registry();
    const std::lock_guard lock(entries.mutex);
    const auto found = entries.schemes.find(uri.scheme);
    known = found != entries.schemes.end();
    if (known) checker = found->second.checker;
  }
  if (!known) throw FrameSourceError("source '" + text + "': unknown scheme '" + uri.scheme + ":'; use one of:" + schemeList());
  if (!playsAtRecordedRate(uri)) (void)uri.getDouble("rate", 0.0, 1e-3, 1e4);
  if (checker) checker(uri);
}

bool playsAtRecordedRate(const SourceUri& uri) { return uri.getString("rate", "") == "recorded"; }

std::unique_ptr<FrameSource> makeRecordedRateSource(std::unique_ptr<FrameSource> inner) {
  return std::make_unique<RateLimitedSource>(std::move(inner), 0.0);
}

std::unique_ptr<FrameSource> makeRateLimitedSource(std::unique_ptr<FrameSource> inner, double rate_hz) {
  if (!(rate_hz > 0)) throw FrameSourceError("rate: must be > 0 Hz");
  return std::make_unique<RateLimitedSource>(std::move(inner), rate_hz);
}

}  // namespace toposlam
