// Conversion of camera buffers to BGR images (camera_pixels.hpp).
#include "camera_pixels.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace toposlam {

int bytesPerPixel(CameraPixelLayout layout) {
  switch (layout) {
    case CameraPixelLayout::Yuyv:
      return 2;
    case CameraPixelLayout::Grey:
      return 1;
    case CameraPixelLayout::Rgb:
    case CameraPixelLayout::Bgr:
      return 3;
    case CameraPixelLayout::Jpeg:
      return 0;
  }
  return 0;
}

std::size_t packedImageBytes(CameraPixelLayout layout, int width, int height, std::size_t stride) {
  const auto row = static_cast<std::size_t>(width) * static_cast<std::size_t>(bytesPerPixel(layout));
  if (row == 0 || height <= 0 || stride < row) return 0;
  return stride * static_cast<std::size_t>(height - 1) + row;
}

cv::Mat cameraBufferToBgr(CameraPixelLayout layout, const std::uint8_t* data, std::size_t bytes, int width,
                          int height, std::size_t stride) {
  // OpenCV only reads through these headers; it wants a non-const pointer.
  auto* pixels = const_cast<std::uint8_t*>(data);
  cv::Mat bgr;
  if (layout == CameraPixelLayout::Jpeg) {
    if (bytes == 0) return bgr;
    try {
      bgr = cv::imdecode(cv::Mat(1, static_cast<int>(bytes), CV_8UC1, pixels), cv::IMREAD_COLOR);
    } catch (const cv::Exception&) {
      bgr.release();
    }
    return bgr;
  }
  const std::size_t needed = packedImageBytes(layout, width, height, stride);
  if (needed == 0 || bytes < needed) return bgr;
  switch (layout) {
    case CameraPixelLayout::Yuyv:
      cv::cvtColor(cv::Mat(height, width, CV_8UC2, pixels, stride), bgr, cv::COLOR_YUV2BGR_YUYV);
      break;
    case CameraPixelLayout::Grey:
      cv::cvtColor(cv::Mat(height, width, CV_8UC1, pixels, stride), bgr, cv::COLOR_GRAY2BGR);
      break;
    case CameraPixelLayout::Rgb:
      cv::cvtColor(cv::Mat(height, width, CV_8UC3, pixels, stride), bgr, cv::COLOR_RGB2BGR);
      break;
    case CameraPixelLayout::Bgr:
      bgr = cv::Mat(height, width, CV_8UC3, pixels, stride).clone();
      break;
    case CameraPixelLayout::Jpeg:
      break;
  }
  return bgr;
}

}  // namespace toposlam
