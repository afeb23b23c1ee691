// cameraBufferToBgr and cameraBufferToImages: every layout the camera backends receive becomes the right BGR
// pixels, strides are honoured, and short or undecodable buffers give an empty image (which the backends
// count as skipped).
#include <catch2/catch.hpp>

#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "camera_pixels.hpp"

using toposlam::CameraPixelLayout;
using toposlam::cameraBufferToBgr;
using toposlam::packedImageBytes;

SCENARIO("GIVEN 2x2 packed buffers with a padded stride WHEN converted THEN the BGR pixels are exact") {
  // Rows 8 bytes apart; the last row is not padded (what packedImageBytes expects at least).
  const std::vector<std::uint8_t> rgb = {10, 20, 30, 40, 50, 60, 0, 0, 70, 80, 90, 100, 110, 120};
  const cv::Mat from_rgb = cameraBufferToBgr(CameraPixelLayout::Rgb, rgb.data(), rgb.size(), 2, 2, 8);
  REQUIRE(from_rgb.type() == CV_8UC3);
  CHECK(from_rgb.at<cv::Vec3b>(0, 0) == cv::Vec3b(30, 20, 10));
  CHECK(from_rgb.at<cv::Vec3b>(1, 1) == cv::Vec3b(120, 110, 100));
  const cv::Mat from_bgr = cameraBufferToBgr(CameraPixelLayout::Bgr, rgb.data(), rgb.size(), 2, 2, 8);
  CHECK(from_bgr.at<cv::Vec3b>(0, 1) == cv::Vec3b(40, 50, 60));
  CHECK(from_bgr.data != rgb.data());  // a copy: the caller's buffer may be re-queued at once
  const std::vector<std::uint8_t> grey = {0, 255, 9, 9, 128, 64};
  const cv::Mat from_grey = cameraBufferToBgr(CameraPixelLayout::Grey, grey.data(), grey.size(), 2, 2, 4);
  CHECK(from_grey.at<cv::Vec3b>(0, 1) == cv::Vec3b(255, 255, 255));
  CHECK(from_grey.at<cv::Vec3b>(1, 0) == cv::Vec3b(128, 128, 128));
  // YUYV with neutral chroma (U = V = 128): grey at the luma of each pixel (BT.601 video range).
  const std::vector<std::uint8_t> yuyv = {16, 128, 235, 128, 16, 128, 235, 128};
  const cv::Mat from_yuyv = cameraBufferToBgr(CameraPixelLayout::Yuyv, yuyv.data(), yuyv.size(), 2, 2, 4);
  REQUIRE(from_yuyv.size() == cv::Size(2, 2));
  const cv::Vec3b dark = from_yuyv.at<cv::Vec3b>(0, 0), light = from_yuyv.at<cv::Vec3b>(1, 1);
  CHECK(dark[0] == dark[2]);
  CHECK(light[0] == light[2]);
  CHECK(static_cast<int>(light[1]) - static_cast<int>(dark[1]) > 200);
}

SCENARIO("GIVEN short packed buffers WHEN converted THEN the image is empty") {
  CHECK(packedImageBytes(CameraPixelLayout::Rgb, 2, 2, 8) == 14);
  CHECK(packedImageBytes(CameraPixelLayout::Yuyv, 640, 480, 1280) == 614400);
  CHECK(packedImageBytes(CameraPixelLayout::Rgb, 2, 2, 5) == 0);  // stride shorter than a row
  const std::vector<std::uint8_t> bytes(13, 0);
  CHECK(cameraBufferToBgr(CameraPixelLayout::Rgb, bytes.data(), bytes.size(), 2, 2, 8).empty());
  CHECK(cameraBufferToBgr(CameraPixelLayout::Rgb, bytes.data(), bytes.size(), 2, 2, 5).empty());
}

SCENARIO("GIVEN JPEG buffers WHEN converted THEN a valid one decodes and garbage or nothing gives empty") {
  cv::Mat image(16, 24, CV_8UC3, cv::Scalar(200, 100, 50));
  std::vector<std::uint8_t> jpeg;
  REQUIRE(cv::imencode(".jpg", image, jpeg));
  const cv::Mat decoded = cameraBufferToBgr(CameraPixelLayout::Jpeg, jpeg.data(), jpeg.size(), 0, 0, 0);
  REQUIRE(decoded.size() == cv::Size(24, 16));
  const cv::Vec3b pixel = decoded.at<cv::Vec3b>(8, 12);
  CHECK(std::abs(pixel[0] - 200) <= 3);
  CHECK(std::abs(pixel[1] - 100) <= 3);
  CHECK(std::abs(pixel[2] - 50) <= 3);
  const std::vector<std::uint8_t> garbage(64, 0x5a);
  CHECK(cameraBufferToBgr(CameraPixelLayout::Jpeg, garbage.data(), garbage.size(), 0, 0, 0).empty());
  CHECK(cameraBufferToBgr(CameraPixelLayout::Jpeg, jpeg.data(), 0, 0, 0, 0).empty());
}

SCENARIO(
    "GIVEN camera buffers WHEN made into a frame's images THEN grey stays grey and YUYV brings its luma") {
  using toposlam::cameraBufferToImages;
  using toposlam::CameraImages;
  GIVEN("a grey camera's 2x2 buffer with a padded stride") {
    const std::vector<std::uint8_t> grey = {0, 255, 9, 9, 128, 64};
    const CameraImages images =
        cameraBufferToImages(CameraPixelLayout::Grey, grey.data(), grey.size(), 2, 2, 4);
    THEN("the image is the grey pixels, copied, never BGR, and it is its own grey") {
      REQUIRE(images.image.type() == CV_8UC1);
      CHECK(images.image.at<std::uint8_t>(0, 1) == 255);
      CHECK(images.image.at<std::uint8_t>(1, 0) == 128);
      CHECK(images.image.at<std::uint8_t>(1, 1) == 64);
      CHECK(images.image.data != grey.data());
      CHECK(images.grey.data == images.image.data);
      CHECK(cameraBufferToImages(CameraPixelLayout::Grey, grey.data(), 5, 2, 2, 4).image.empty());
    }
  }
  GIVEN("a YUYV buffer of every luma level, neutral and coloured chroma") {
    // 256 x 3 pixels: row 0 neutral (U = V = 128), rows 1 and 2 moderately coloured.
    const int width = 256, height = 3;
    std::vector<std::uint8_t> yuyv(static_cast<std::size_t>(width * height * 2));
    const int chroma[3][2] = {{128, 128}, {100, 150}, {150, 110}};
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const std::size_t at = static_cast<std::size_t>((y * width + x) * 2);
        yuyv[at] = static_cast<std::uint8_t>(x);
        yuyv[at + 1] = static_cast<std::uint8_t>(chroma[y][x % 2]);
      }
    const CameraImages images =
        cameraBufferToImages(CameraPixelLayout::Yuyv, yuyv.data(), yuyv.size(), width, height, width * 2);
    cv::Mat bgr =
        cameraBufferToBgr(CameraPixelLayout::Yuyv, yuyv.data(), yuyv.size(), width, height, width * 2);
    cv::Mat round_trip;
    cv::cvtColor(bgr, round_trip, cv::COLOR_BGR2GRAY);
    THEN("the image is the same BGR and the luma is the round trip's grey where the chroma is neutral") {
      CHECK(cv::norm(images.image, bgr, cv::NORM_INF) == 0);
      REQUIRE(images.grey.type() == CV_8UC1);
      CHECK(cv::norm(images.grey.row(0), round_trip.row(0), cv::NORM_INF) == 0);
      for (int level = 0; level < 256; ++level)  // the table, and the arithmetic that stands for it
        CHECK(images.grey.at<std::uint8_t>(0, level) ==
              toposlam::yuyvLumaToGrey()[static_cast<std::size_t>(level)]);
      CHECK(images.grey.at<std::uint8_t>(0, 16) == 0);     // video black
      CHECK(images.grey.at<std::uint8_t>(0, 235) == 255);  // video white
    }
    THEN("where it is coloured, only the decoder's clipping and rounding separate them") {
      // Measured: away from clipping (luma 60..179) one rounding step at most; near black and white,
      // where the decoder clips a channel, up to 11 levels.
      CHECK(cv::norm(images.grey(cv::Rect(60, 1, 120, 2)), round_trip(cv::Rect(60, 1, 120, 2)),
                     cv::NORM_INF) == 1);
      CHECK(cv::norm(images.grey.rowRange(1, 3), round_trip.rowRange(1, 3), cv::NORM_INF) == 11);
    }
  }
  GIVEN("BGR, RGB or JPEG buffers") {
    const std::vector<std::uint8_t> rgb = {10, 20, 30, 40, 50, 60, 0, 0, 70, 80, 90, 100, 110, 120};
    const CameraImages images = cameraBufferToImages(CameraPixelLayout::Rgb, rgb.data(), rgb.size(), 2, 2, 8);
    THEN("they carry no grey of their own") {
      CHECK(images.image.type() == CV_8UC3);
      CHECK(images.grey.empty());
    }
  }
}
