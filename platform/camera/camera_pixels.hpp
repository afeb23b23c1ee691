// Camera buffers to the pipeline's BGR images: the conversion both camera backends (v4l2:, libcamera:)
// need, in one place. A layout is named by its byte order in memory, so V4L2's BGR24 and libcamera's
// RGB888 (both B,G,R bytes) are the same `Bgr`, and V4L2's RGB24 and libcamera's BGR888 the same `Rgb`.
// Each backend maps its own format codes to a layout and keeps its zero-copy path for `Bgr` (an image
// viewing the driver's buffer, handed back by the frame's lease). Plain functions: thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>

#include <opencv2/core/mat.hpp>

namespace toposlam {

enum class CameraPixelLayout {
  Yuyv,  ///< packed 4:2:2, Y0 U Y1 V (V4L2 YUYV, libcamera YUYV)
  Grey,  ///< one byte per pixel (V4L2 GREY)
  Rgb,   ///< R,G,B bytes (V4L2 RGB24, libcamera BGR888)
  Bgr,   ///< B,G,R bytes: OpenCV's order (V4L2 BGR24, libcamera RGB888)
  Jpeg,  ///< one (M)JPEG image (V4L2 MJPEG/JPEG, libcamera MJPEG)
};

/// Bytes per pixel of a packed layout (Yuyv 2, Grey 1, Rgb and Bgr 3); 0 for Jpeg.
int bytesPerPixel(CameraPixelLayout layout);

/// Fewest bytes that hold `height` rows of `width` pixels `stride` bytes apart (the last row need not be
/// padded); 0 for Jpeg, or for a stride shorter than a row.
std::size_t packedImageBytes(CameraPixelLayout layout, int width, int height, std::size_t stride);

/// A BGR image (CV_8UC3) that owns its pixels, made from one camera buffer of `bytes` bytes: packed
/// layouts are `height` rows of `width` pixels, `stride` bytes apart (Bgr is copied); Jpeg is decoded
/// (`width`, `height` and `stride` unused). Empty when a packed buffer is shorter than
/// packedImageBytes(), or the JPEG is empty or does not decode: the caller counts it as a skipped frame.
cv::Mat cameraBufferToBgr(CameraPixelLayout layout, const std::uint8_t* data, std::size_t bytes, int width,
                          int height, std::size_t stride);

}  // namespace toposlam
