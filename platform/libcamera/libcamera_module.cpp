// The entry point of the loadable libcamera module (toposlam-source-libcamera.so): openFrameSource loads
// it the first time a `libcamera:` URI is opened (platform/files/source_modules.cpp) and calls this
// function, so a program that never opens a libcamera camera does not load libcamera and the ~30 shared
// libraries behind it (GnuTLS, lttng-ust, which reads every loaded library's ELF at start, libdw, ...).
// Its C name and signature, with the FrameSource class it returns, are the module's whole interface; the
// version suffix changes with any change to them (_v2: FrameSource::realTime).
// It never throws: a failure comes back as a null pointer and a message.
#include <exception>
#include <string>

#include "libcamera_frame_source.hpp"

extern "C" __attribute__((visibility("default"))) toposlam::FrameSource* toposlam_source_libcamera_open_v2(
    const char* uri, std::string* error) {
  try {
    return new toposlam::LibcameraFrameSource(toposlam::parseLibcameraUri(std::string(uri)));
  } catch (const std::exception& e) {
    if (error) *error = e.what();
  } catch (...) {
    if (error) *error = "libcamera: unknown error opening '" + std::string(uri) + "'";
  }
  return nullptr;
}
