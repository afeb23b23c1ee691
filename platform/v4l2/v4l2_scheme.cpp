// Plugs `v4l2:` into the frame-source factory (openFrameSource), so every app opens cameras by URI.
#include "toposlam/io/source_factory.hpp"
#include "v4l2_frame_source.hpp"

namespace toposlam {

void registerV4l2FrameSourceScheme(bool wait_at_start) {
  registerFrameSourceScheme(
      "v4l2",
      [wait_at_start](const SourceUri& uri) -> std::unique_ptr<FrameSource> {
        V4l2SourceConfig defaults;
        defaults.wait_at_start = wait_at_start;
        return std::make_unique<V4l2FrameSource>(parseV4l2Uri(uri, defaults));
      },
      "v4l2:/dev/videoN?size=WxH&fps=F&format=yuyv|mjpeg|grey|bgr24|rgb24&buffers=N&wait=0|1",
      // --check-config: the options judged as the opener judges them; the device is not opened.
      [wait_at_start](const SourceUri& uri) {
        V4l2SourceConfig defaults;
        defaults.wait_at_start = wait_at_start;
        (void)parseV4l2Uri(uri, defaults);
      });
}

}  // namespace toposlam
