// Opening frame sources by URI, through a registry of scheme -> opener function.
//
// Built in: `images:PATH_OR_GLOB`, `video:FILE`, `libcamera:ID?...` (both through modules loaded on first
// use: source_modules.hpp), `sim:WORLD?route=R&fps=F&size=WxH&seed=S&...`, and a plain path (a folder ->
// images, a video file -> video, an image file -> images). Other platform adapters (v4l2) call
// registerFrameSourceScheme() once at start-up, before opening.
// The common query key `rate=HZ` plays the source in real time at that rate (the returned source sleeps
// between frames); `rate=recorded` plays it at the pace of its own frame timestamps (a recording made by
// `toposlam capture --record`, whose timestamps.csv the images: source reads); without it frames come as
// fast as they are asked for.
// Thread-safety: registering and opening may be called from any thread (the registry is locked).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "toposlam/io/source_uri.hpp"
#include "toposlam/pipeline/frame_source.hpp"

namespace toposlam {

/// Builds a source from a parsed URI; throws FrameSourceError with an actionable message.
using FrameSourceOpener = std::function<std::unique_ptr<FrameSource>(const SourceUri&)>;

/// Checks a parsed URI's options as its opener would, opening nothing (no device, no file); throws
/// FrameSourceError with the opener's message for a bad key or value.
using FrameSourceChecker = std::function<void(const SourceUri&)>;

/// Adds or replaces a scheme (lower case letters, digits, '_' or '-'). `usage` is shown in errors,
/// e.g. "v4l2:/dev/videoN?size=WxH&fps=F&format=F". `checker` (optional) lets checkFrameSourceUri judge the
/// options without opening.
void registerFrameSourceScheme(const std::string& scheme, FrameSourceOpener opener, const std::string& usage,
                               FrameSourceChecker checker = {});
/// Registered schemes with their usage strings, sorted by scheme.
std::vector<std::pair<std::string, std::string>> registeredFrameSourceSchemes();

/// What openFrameSource would refuse about `uri` before opening anything: its syntax, an unknown scheme, the
/// scheme's keys and values (through its checker, when it has one) and the common `rate`. Throws
/// FrameSourceError with the same message as openFrameSource; opens no device and reads no file. A plain path
/// (no scheme) is left to the caller.
void checkFrameSourceUri(const std::string& uri);

/// Opens a source; throws FrameSourceError naming the unknown scheme, bad key or bad value.
std::unique_ptr<FrameSource> openFrameSource(const std::string& uri);

/// Wraps a source so next() returns frame k no earlier than k / rate_hz seconds after the first call
/// (sleeps on a steady clock). Timestamps are left as the inner source set them.
std::unique_ptr<FrameSource> makeRateLimitedSource(std::unique_ptr<FrameSource> inner, double rate_hz);

/// Wraps a source so next() returns each frame no earlier than its timestamp minus the first frame's
/// after the first call: the pace it was recorded at (gaps included; a timestamp going back is due one
/// typical frame interval after the frame before, FrameTimeline). Timestamps are left as they are.
std::unique_ptr<FrameSource> makeRecordedRateSource(std::unique_ptr<FrameSource> inner);

/// True when `uri` asks for rate=recorded (the openers then leave `rate` to openFrameSource).
bool playsAtRecordedRate(const SourceUri& uri);

}  // namespace toposlam
