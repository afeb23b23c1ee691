// The frame-source registry and factory (source_factory.hpp), with the built-in schemes images:,
// video: and sim:, plain paths, and the real-time `rate` wrapper.
#include "toposlam/io/source_factory.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

#include "toposlam/io/file_sources.hpp"
#include "toposlam/io/sim_source.hpp"

namespace toposlam {

namespace {

struct SchemeEntry {
  FrameSourceOpener opener;
  std::string usage;
};

class RateLimitedSource : public FrameSource {
 public:
  RateLimitedSource(std::unique_ptr<FrameSource> inner, double rate_hz) : inner_(std::move(inner)), rate_hz_(rate_hz) {}
  std::string describe() const override {
    return inner_->describe() + " at " + std::to_string(rate_hz_) + " Hz real time";
  }
  std::optional<Frame> next() override {
    std::optional<Frame> frame = inner_->next();
    if (!frame) return frame;
    const auto now = std::chrono::steady_clock::now();
    if (delivered_ == 0) start_ = now;
    const auto due = start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                  std::chrono::duration<double>(static_cast<double>(delivered_) / rate_hz_));
    if (due > now) std::this_thread::sleep_until(due);
    ++delivered_;
    return frame;
  }
  std::int64_t skippedFrames() const override { return inner_->skippedFrames(); }
  std::int64_t frameCountHint() const override { return inner_->frameCountHint(); }

 private:
  std::unique_ptr<FrameSource> inner_;
  double rate_hz_;
  std::chrono::steady_clock::time_point start_;
  std::int64_t delivered_ = 0;
};

std::unique_ptr<FrameSource> openImages(const SourceUri& uri) {
  uri.requireOnly({});
  if (uri.path.empty()) throw FrameSourceError("source '" + uri.text + "': images: needs a folder, file or glob");
  return std::make_unique<ImageFilesSource>(uri.path, uri.getDouble("rate", 1.0, 1e-3, 1e4));
}

std::unique_ptr<FrameSource> openVideo(const SourceUri& uri) {
  uri.requireOnly({});
  if (uri.path.empty()) throw FrameSourceError("source '" + uri.text + "': video: needs a file");
  return std::make_unique<VideoFileSource>(uri.path, uri.getDouble("rate", 0.0, 1e-3, 1e4));
}

std::unique_ptr<FrameSource> openSim(const SourceUri& uri) { return std::make_unique<SimFrameSource>(simConfigFromUri(uri)); }

struct Registry {
  std::mutex mutex;
  std::map<std::string, SchemeEntry> schemes;
  Registry() {
    schemes["images"] = {openImages, "images:FOLDER_OR_GLOB[?rate=HZ]"};
    schemes["video"] = {openVideo, "video:FILE[?rate=HZ]"};
    schemes["sim"] = {openSim,
                      "sim:WORLD?route=R&fps=F&size=WxH&seed=S[&speed=&fov=&light=day|night|warm|cool&noise=&people=&"
                      "pitch=&moved=0|1&rate=HZ]"};
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

void registerFrameSourceScheme(const std::string& scheme, FrameSourceOpener opener, const std::string& usage) {
  const bool valid = !scheme.empty() && std::all_of(scheme.begin(), scheme.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  });
  if (!valid || !opener) throw FrameSourceError("registerFrameSourceScheme: bad scheme '" + scheme + "' or no opener");
  Registry& entries = registry();
  const std::lock_guard lock(entries.mutex);
  entries.schemes[scheme] = {std::move(opener), usage};
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
  const double rate = uri.getDouble("rate", 0.0, 1e-3, 1e4);
  std::unique_ptr<FrameSource> source = opener(uri);
  if (rate > 0) source = makeRateLimitedSource(std::move(source), rate);
  return source;
}

std::unique_ptr<FrameSource> makeRateLimitedSource(std::unique_ptr<FrameSource> inner, double rate_hz) {
  if (!(rate_hz > 0)) throw FrameSourceError("rate: must be > 0 Hz");
  return std::make_unique<RateLimitedSource>(std::move(inner), rate_hz);
}

}  // namespace toposlam
