// See sources.hpp. The camera adapters register their URI schemes (v4l2:, libcamera:) once, before the
// first source is opened.
#include "sources.hpp"

#include <mutex>

#ifdef TOPOSLAM_HAVE_SOURCES
#include "toposlam/io/source_factory.hpp"
#endif
#ifdef TOPOSLAM_HAVE_V4L2
#include "toposlam/io/v4l2_frame_source.hpp"
#endif
#ifdef TOPOSLAM_HAVE_LIBCAMERA
#include "toposlam/io/libcamera_frame_source.hpp"
#endif

namespace toposlam::daemon {

std::unique_ptr<FrameSource> openSource(const std::string& uri) {
#ifdef TOPOSLAM_HAVE_SOURCES
  static std::once_flag registered;
  std::call_once(registered, [] {
#ifdef TOPOSLAM_HAVE_V4L2
    registerV4l2FrameSourceScheme();
#endif
#ifdef TOPOSLAM_HAVE_LIBCAMERA
    registerLibcameraFrameSourceScheme();
#endif
  });
  return openFrameSource(uri);
#else
  throw FrameSourceError("cannot open '" + uri + "': this build has no frame sources (toposlam_sources was not "
                         "built; see io/source_factory.hpp)");
#endif
}

}  // namespace toposlam::daemon
