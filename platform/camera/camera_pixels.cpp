// Conversion of camera buffers to the pipeline's images (camera_pixels.hpp).
#include "camera_pixels.hpp"

#include <opencv2/imgproc.hpp>

#include "toposlam/io/image_codec.hpp"

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
      // A frame claiming more than four times the negotiated pixels is garbage, not a picture.
      const std::int64_t cap = std::max<std::int64_t>(std::int64_t{4} * width * height, std::int64_t{1} << 20);
      bgr = decodeImage(data, bytes, ImageColor::Bgr, cap);
    } catch (const ImageCodecError&) {
      bgr.release();
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

std::vector<std::uint8_t> bgrToYuyv(const cv::Mat& bgr) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(bgr.rows) * static_cast<std::size_t>(bgr.cols / 2) *
                                4);
  std::size_t k = 0;
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x + 1 < bgr.cols; x += 2) {
      double u = 0.0, v = 0.0, luma[2];
      for (int i = 0; i < 2; ++i) {
        const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x + i);
        const double b = p[0], g = p[1], r = p[2];
        luma[i] = 16.0 + (65.481 * r + 128.553 * g + 24.966 * b) / 255.0;
        u += 128.0 + (-37.797 * r - 74.203 * g + 112.0 * b) / 255.0;
        v += 128.0 + (112.0 * r - 93.786 * g - 18.214 * b) / 255.0;
      }
      out[k++] = cv::saturate_cast<std::uint8_t>(luma[0]);
      out[k++] = cv::saturate_cast<std::uint8_t>(u / 2.0);
      out[k++] = cv::saturate_cast<std::uint8_t>(luma[1]);
      out[k++] = cv::saturate_cast<std::uint8_t>(v / 2.0);
    }
  }
  return out;
}

const std::array<std::uint8_t, 256>& yuyvLumaToGrey() {
  // Made by the decoder itself: one row of 256 pixels, Y = 0..255 with U = V = 128, decoded to BGR;
  // with neutral chroma B = G = R, which BGR-to-grey leaves as it is.
  static const std::array<std::uint8_t, 256> table = [] {
    std::array<std::uint8_t, 512> yuyv{};
    for (int x = 0; x < 256; ++x) {
      yuyv[static_cast<std::size_t>(2 * x)] = static_cast<std::uint8_t>(x);
      yuyv[static_cast<std::size_t>(2 * x + 1)] = 128;
    }
    cv::Mat bgr;
    cv::cvtColor(cv::Mat(1, 256, CV_8UC2, yuyv.data()), bgr, cv::COLOR_YUV2BGR_YUYV);
    std::array<std::uint8_t, 256> t{};
    for (int x = 0; x < 256; ++x) t[static_cast<std::size_t>(x)] = bgr.at<cv::Vec3b>(0, x)[1];
    return t;
  }();
  return table;
}

CameraImages cameraBufferToImages(CameraPixelLayout layout, const std::uint8_t* data, std::size_t bytes,
                                  int width, int height, std::size_t stride) {
  CameraImages out;
  if (layout == CameraPixelLayout::Grey) {
    const std::size_t needed = packedImageBytes(layout, width, height, stride);
    if (needed == 0 || bytes < needed) return out;
    // OpenCV only reads through this header; it wants a non-const pointer.
    out.image = cv::Mat(height, width, CV_8UC1, const_cast<std::uint8_t*>(data), stride).clone();
    out.grey = out.image;
    return out;
  }
  out.image = cameraBufferToBgr(layout, data, bytes, width, height, stride);
  if (layout == CameraPixelLayout::Yuyv && !out.image.empty()) {
    // yuyvLumaToGrey() as arithmetic the compiler vectorises (16-bit lanes): min(255, (max(Y - 16, 0)
    // x 149 + 62) >> 7) equals the table for all 256 values (tested); a table look-up per pixel cost
    // more than the BGR-to-grey conversion it replaces.
    out.grey.create(height, width, CV_8UC1);
    for (int y = 0; y < height; ++y) {
      const std::uint8_t* in = data + static_cast<std::size_t>(y) * stride;  // Y0 U Y1 V ...
      std::uint8_t* row = out.grey.ptr<std::uint8_t>(y);
      for (int x = 0; x < width; ++x) {
        const std::uint16_t above_black = in[2 * x] > 16 ? static_cast<std::uint16_t>(in[2 * x] - 16) : 0;
        const auto grey = static_cast<std::uint16_t>((above_black * 149 + 62) >> 7);
        row[x] = static_cast<std::uint8_t>(grey > 255 ? 255 : grey);
      }
    }
  }
  return out;
}

}  // namespace toposlam
