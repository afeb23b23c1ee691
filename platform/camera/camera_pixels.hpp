// Camera buffers to the pipeline's images: the conversion both camera backends (v4l2:, libcamera:)
// need, in one place. A frame is handed on in the camera's own terms where that saves work: a grey
// camera's frames stay grey (never made BGR to be made grey again), and a YUYV camera's luma goes with
// the BGR image, so edges and keypoints need not convert colour back to grey. A layout is named by its byte
// order in memory, so V4L2's BGR24 and libcamera's RGB888 (both B,G,R bytes) are the same `Bgr`, and V4L2's
// RGB24 and libcamera's BGR888 the same `Rgb`. Each backend maps its own format codes to a layout and keeps
// its zero-copy path for `Bgr` (an image viewing the driver's buffer, handed back by the frame's lease).
// Plain functions: thread-safe.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

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

/// What a frame carries from one camera buffer (see Frame): `image` and, when the camera has one,
/// its own `grey`.
struct CameraImages {
  cv::Mat image;  ///< BGR (CV_8UC3); a Grey camera's pixels themselves (CV_8UC1); empty as above
  cv::Mat grey;   ///< Yuyv: the luma; Grey: the same pixels as `image`; else empty
};

/// As cameraBufferToBgr(), but a Grey buffer stays grey, and a Yuyv buffer also gives its luma, taken
/// from the Y bytes through one table: the grey OpenCV's BT.601 (video range) decoder gives a pixel of
/// that Y and neutral chroma, so for grey scenes it equals converting the BGR image to grey, and for
/// coloured ones it differs by the decoder's per-channel clipping and rounding (docs/performance.md).
CameraImages cameraBufferToImages(CameraPixelLayout layout, const std::uint8_t* data, std::size_t bytes,
                                  int width, int height, std::size_t stride);

/// What a YUYV camera delivers of a BGR image (CV_8UC3, even width): BT.601 video range (Y 16..235),
/// the chroma of each pixel pair averaged, rows packed (stride = 2 x width). For tests and benchmarks
/// that play recorded colour frames as a YUYV camera.
std::vector<std::uint8_t> bgrToYuyv(const cv::Mat& bgr);

/// The table behind the Yuyv luma: video-range Y (16..235) to grey (0..255).
const std::array<std::uint8_t, 256>& yuyvLumaToGrey();

}  // namespace toposlam
