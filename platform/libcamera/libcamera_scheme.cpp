// Plugs `libcamera:` into the frame-source factory (openFrameSource), so every app opens cameras by URI.
#include "libcamera_frame_source.hpp"
#include "toposlam/io/source_factory.hpp"

namespace toposlam {

void registerLibcameraFrameSourceScheme() {
  registerFrameSourceScheme(
      "libcamera",
      [](const SourceUri& uri) -> std::unique_ptr<FrameSource> {
        return std::make_unique<LibcameraFrameSource>(parseLibcameraUri(uri));
      },
      "libcamera:ID?size=WxH&buffers=N (empty ID: the first camera)");
}

}  // namespace toposlam
