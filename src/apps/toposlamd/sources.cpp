// See sources.hpp. The V4L2 adapter registers its URI scheme (v4l2:) once, before the first source is
// opened (libcamera: is the factory's own, through a module loaded on first use). A V4L2 camera that is
// not plugged in yet does not stop the service: it starts reconnecting (status "camera reconnecting") and
// opens the camera when it appears (URI wait=0 opts out).
#include "sources.hpp"

#include <filesystem>
#include <mutex>

#include "toposlam/io/source_factory.hpp"
#include "toposlam/io/source_uri.hpp"
#include "v4l2_frame_source.hpp"

namespace toposlam::daemon {

namespace {

void registerCameraSchemes() {
  static std::once_flag registered;
  std::call_once(registered, [] {
    registerV4l2FrameSourceScheme(/*wait_at_start=*/true);
  });
}

}  // namespace

std::string checkSourceUri(const std::string& uri) {
  registerCameraSchemes();
  try {
    const SourceUri parsed = parseSourceUri(uri);
    if (parsed.scheme.empty()) {
      std::error_code error;
      if (!std::filesystem::exists(parsed.path, error) && parsed.path.find_first_of("*?[") == std::string::npos)
        return "'" + uri + "' has no scheme and is no existing file or folder (e.g. images:DIR, v4l2:/dev/video0)";
      return "";
    }
    checkFrameSourceUri(uri);  // the scheme, its keys and values, as the start judges them; nothing opened
    return "";
  } catch (const std::exception& e) {
    // The factory says "source '<uri>': ..."; the caller names the key (source:) already.
    const std::string problem = e.what();
    return problem.rfind("source '", 0) == 0 ? problem.substr(7) : problem;
  }
}

std::string mapSourceOf(const std::string& uri) { return sourceIdentity(uri); }

std::unique_ptr<FrameSource> openSource(const std::string& uri) {
  registerCameraSchemes();
  return openFrameSource(uri);
}

}  // namespace toposlam::daemon
