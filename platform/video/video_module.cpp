// The entry point of the loadable video module (toposlam-source-video.so): openFrameSource loads it
// the first time a `video:` URI is opened (platform/files/source_modules.cpp) and calls this function.
// Its C name and signature, with the FrameSource class it returns, are the module's whole interface; the
// version suffix changes with any change to them (_v2: FrameSource::realTime).
// It never throws: a failure comes back as a null pointer and a message.
#include <exception>
#include <string>

#include "video_file_source.hpp"

extern "C" __attribute__((visibility("default"))) toposlam::FrameSource* toposlam_source_video_open_v2(
    const char* path, double timestamp_rate_hz, std::string* error) {
  try {
    return new toposlam::VideoFileSource(path, timestamp_rate_hz);
  } catch (const std::exception& e) {
    if (error) *error = e.what();
  } catch (...) {
    if (error) *error = "video: unknown error opening '" + std::string(path) + "'";
  }
  return nullptr;
}
