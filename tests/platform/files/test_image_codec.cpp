// Tests of image_codec.hpp against OpenCV's imgcodecs, which it replaces: the same pixels from the same
// bytes (the bundled JPEG frames, PNG and BMP in the layouts OpenCV writes, EXIF orientations), the
// same JPEG bytes from the same image and quality, and clear errors for what it does not read.
#include <catch2/catch.hpp>

#include <algorithm>

#include <filesystem>
#include <fstream>
#include <iterator>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "toposlam/io/image_codec.hpp"

using namespace toposlam;

namespace {

const std::string kSamples = std::string(TOPOSLAM_SAMPLES_DIR) + "/samples";

std::vector<unsigned char> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

bool samePixels(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  return cv::norm(a, b, cv::NORM_INF) == 0;
}

cv::Mat decode(const std::vector<unsigned char>& bytes, ImageColor color) {
  return decodeImage(bytes.data(), bytes.size(), color);
}

cv::Mat opencv(const std::vector<unsigned char>& bytes, int flags) { return cv::imdecode(bytes, flags); }

/// A test picture with structure in every channel (gradients, a disc, noise).
cv::Mat testPicture(int width, int height, int type) {
  cv::Mat bgr(height, width, CV_8UC3);
  cv::RNG rng(7);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(x * 255 / width), static_cast<uchar>(y * 255 / height),
                                          static_cast<uchar>(rng.uniform(0, 256)));
  cv::circle(bgr, {width / 2, height / 2}, height / 3, cv::Scalar(30, 200, 90), -1);
  if (type == CV_8UC3) return bgr;
  cv::Mat out;
  if (type == CV_8UC1) cv::cvtColor(bgr, out, cv::COLOR_BGR2GRAY);
  if (type == CV_8UC4) cv::cvtColor(bgr, out, cv::COLOR_BGR2BGRA);
  if (type == CV_16UC3) bgr.convertTo(out, CV_16UC3, 257.0);
  return out;
}

/// `jpeg` with an APP1 EXIF segment saying `orientation` inserted after SOI (big-endian TIFF, one IFD entry).
std::vector<unsigned char> withExifOrientation(const std::vector<unsigned char>& jpeg, int orientation) {
  const std::vector<unsigned char> tiff = {'M', 'M', 0, 42, 0, 0, 0, 8,  // header, IFD0 at 8
                                           0, 1,                          // one entry
                                           0x01, 0x12, 0, 3, 0, 0, 0, 1, 0, static_cast<unsigned char>(orientation), 0, 0,
                                           0, 0, 0, 0};                   // no next IFD
  std::vector<unsigned char> app1 = {0xFF, 0xE1, 0, 0, 'E', 'x', 'i', 'f', 0, 0};
  app1.insert(app1.end(), tiff.begin(), tiff.end());
  const std::size_t length = app1.size() - 2;
  app1[2] = static_cast<unsigned char>(length >> 8);
  app1[3] = static_cast<unsigned char>(length & 0xFF);
  std::vector<unsigned char> out;
  out.reserve(jpeg.size() + app1.size());
  for (std::size_t i = 0; i < jpeg.size(); ++i) {
    out.push_back(jpeg[i]);
    if (i == 1) out.insert(out.end(), app1.begin(), app1.end());  // right after SOI
  }
  return out;
}

}  // namespace

TEST_CASE("GIVEN the bundled JPEG frames WHEN decoded as colour, grey and as stored THEN the pixels equal OpenCV's",
          "[io][image][codec]") {
  for (int i = 1; i <= 84; i += 7) {
    const auto bytes = readBytes(kSamples + "/" + std::to_string(i) + ".jpg");
    INFO("frame " << i);
    CHECK(samePixels(decode(bytes, ImageColor::Bgr), opencv(bytes, cv::IMREAD_COLOR)));
    CHECK(samePixels(decode(bytes, ImageColor::Grey), opencv(bytes, cv::IMREAD_GRAYSCALE)));
    CHECK(samePixels(decode(bytes, ImageColor::AsStored), opencv(bytes, cv::IMREAD_ANYCOLOR)));
  }
  const auto corridor = readBytes(std::string(TOPOSLAM_CORRIDOR_DIR) + "/ref/0000000.jpg");
  REQUIRE(!corridor.empty());
  CHECK(samePixels(decode(corridor, ImageColor::Bgr), opencv(corridor, cv::IMREAD_COLOR)));
}

TEST_CASE("GIVEN grey and colour JPEGs OpenCV wrote WHEN decoded every way THEN the pixels equal OpenCV's",
          "[io][image][codec]") {
  for (int type : {CV_8UC1, CV_8UC3}) {
    std::vector<unsigned char> jpeg;
    REQUIRE(cv::imencode(".jpg", testPicture(97, 61, type), jpeg, {cv::IMWRITE_JPEG_QUALITY, 90}));
    for (auto [color, flags] : {std::pair{ImageColor::Bgr, cv::IMREAD_COLOR}, {ImageColor::Grey, cv::IMREAD_GRAYSCALE},
                                {ImageColor::AsStored, cv::IMREAD_ANYCOLOR}}) {
      INFO("type " << type << " flags " << flags);
      CHECK(samePixels(decode(jpeg, color), opencv(jpeg, flags)));
    }
  }
}

TEST_CASE("GIVEN a JPEG with each EXIF orientation WHEN decoded THEN it is turned upright as OpenCV turns it",
          "[io][image][codec]") {
  std::vector<unsigned char> jpeg;
  REQUIRE(cv::imencode(".jpg", testPicture(64, 40, CV_8UC3), jpeg));
  for (int orientation = 1; orientation <= 8; ++orientation) {
    const auto rotated = withExifOrientation(jpeg, orientation);
    INFO("orientation " << orientation);
    const cv::Mat ours = decode(rotated, ImageColor::Bgr);
    CHECK(ours.cols == (orientation >= 5 ? 40 : 64));
    CHECK(samePixels(ours, opencv(rotated, cv::IMREAD_COLOR)));
    CHECK(samePixels(decode(rotated, ImageColor::Grey), opencv(rotated, cv::IMREAD_GRAYSCALE)));
  }
}

TEST_CASE("GIVEN PNGs of every layout OpenCV writes WHEN decoded every way THEN the pixels equal OpenCV's",
          "[io][image][codec]") {
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC3}) {
    std::vector<unsigned char> png;
    REQUIRE(cv::imencode(".png", testPicture(53, 31, type), png));
    for (auto [color, flags] : {std::pair{ImageColor::Bgr, cv::IMREAD_COLOR}, {ImageColor::Grey, cv::IMREAD_GRAYSCALE},
                                {ImageColor::AsStored, cv::IMREAD_ANYCOLOR}}) {
      INFO("type " << cv::typeToString(type) << " flags " << flags);
      CHECK(samePixels(decode(png, color), opencv(png, flags)));
    }
  }
}

TEST_CASE("GIVEN BMPs (8-bit grey palette, 24-bit) and the bundled ground-truth matrix WHEN decoded THEN equal to OpenCV's",
          "[io][image][codec]") {
  std::vector<std::vector<unsigned char>> files = {readBytes(std::string(TOPOSLAM_SAMPLES_DIR) + "/samples_GT.bmp")};
  for (int type : {CV_8UC1, CV_8UC3}) {
    files.emplace_back();
    REQUIRE(cv::imencode(".bmp", testPicture(45, 23, type), files.back()));  // odd width: padded rows
  }
  for (const auto& bmp : files) {
    for (auto [color, flags] : {std::pair{ImageColor::Bgr, cv::IMREAD_COLOR}, {ImageColor::Grey, cv::IMREAD_GRAYSCALE},
                                {ImageColor::AsStored, cv::IMREAD_ANYCOLOR}}) {
      INFO("size " << bmp.size() << " flags " << flags);
      CHECK(samePixels(decode(bmp, color), opencv(bmp, flags)));
    }
  }
}

TEST_CASE("GIVEN PGM and PPM, ASCII and binary WHEN decoded THEN the samples are read as written, RGB made BGR",
          "[io][image][codec]") {
  const std::string ascii = "P2\n# a comment\n3 2\n255\n0 10 20\n30 40 300\n";
  const std::vector<unsigned char> pgm(ascii.begin(), ascii.end());
  const cv::Mat grey = decode(pgm, ImageColor::AsStored);
  REQUIRE(grey.type() == CV_8UC1);
  CHECK(grey.at<uchar>(0, 1) == 10);
  CHECK(grey.at<uchar>(1, 2) == 255);  // above the maximum: the maximum
  CHECK(decode(pgm, ImageColor::Bgr).type() == CV_8UC3);
  std::vector<unsigned char> ppm = {'P', '6', ' ', '2', ' ', '1', ' ', '2', '5', '5', '\n', 1, 2, 3, 4, 5, 6};
  const cv::Mat colour = decode(ppm, ImageColor::AsStored);
  REQUIRE(colour.type() == CV_8UC3);
  CHECK(colour.at<cv::Vec3b>(0, 0) == cv::Vec3b(3, 2, 1));
  CHECK(colour.at<cv::Vec3b>(0, 1) == cv::Vec3b(6, 5, 4));
  CHECK(samePixels(decode(ppm, ImageColor::AsStored), opencv(ppm, cv::IMREAD_ANYCOLOR)));
  std::vector<unsigned char> big_ppm;
  REQUIRE(cv::imencode(".ppm", testPicture(33, 21, CV_8UC3), big_ppm));
  for (auto [color, flags] : {std::pair{ImageColor::Bgr, cv::IMREAD_COLOR}, {ImageColor::Grey, cv::IMREAD_GRAYSCALE},
                              {ImageColor::AsStored, cv::IMREAD_ANYCOLOR}}) {
    INFO("flags " << flags);
    CHECK(samePixels(decode(big_ppm, color), opencv(big_ppm, flags)));
  }
  CHECK(samePixels(decode(pgm, ImageColor::AsStored), opencv(pgm, cv::IMREAD_ANYCOLOR)));
  ppm.pop_back();
  CHECK_THROWS_WITH(decode(ppm, ImageColor::Bgr), Catch::Contains("PNM pixel data is cut short"));
}

TEST_CASE("GIVEN an image WHEN encoded as JPEG THEN the bytes are OpenCV's at the same quality, and PNG and BMP "
          "round-trip exactly",
          "[io][image][codec]") {
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4}) {
    const cv::Mat picture = testPicture(81, 47, type);
    INFO("type " << cv::typeToString(type));
    for (int quality : {80, 95}) {
      std::vector<unsigned char> theirs;
      REQUIRE(cv::imencode(".jpg", picture, theirs, {cv::IMWRITE_JPEG_QUALITY, quality}));
      CHECK(encodeImage(picture, ImageFormat::Jpeg, quality) == theirs);
    }
    const cv::Mat opaque = type == CV_8UC4 ? testPicture(81, 47, CV_8UC3) : picture;
    const auto png = encodeImage(picture, ImageFormat::Png);
    CHECK(samePixels(opencv(png, cv::IMREAD_UNCHANGED), picture));
    CHECK(samePixels(decode(png, ImageColor::AsStored), opaque));
    const auto bmp = encodeImage(picture, ImageFormat::Bmp);
    CHECK(samePixels(opencv(bmp, cv::IMREAD_ANYCOLOR), opaque));
    CHECK(samePixels(decode(bmp, ImageColor::AsStored), opaque));
  }
  std::vector<unsigned char> reused;
  encodeImage(testPicture(16, 16, CV_8UC3), ImageFormat::Jpeg, reused, 50);
  const std::size_t first = reused.size();
  encodeImage(testPicture(16, 16, CV_8UC3), ImageFormat::Jpeg, reused, 50);
  CHECK(reused.size() == first);  // replaced, not appended
  CHECK_THROWS_AS(encodeImage(cv::Mat(), ImageFormat::Png), ImageCodecError);
  CHECK_THROWS_WITH(encodeImage(cv::Mat(4, 4, CV_32FC1), ImageFormat::Png), Catch::Contains("8-bit"));
  CHECK(imageFormatOfPath("out/drawn.PNG") == ImageFormat::Png);
  CHECK(imageFormatOfPath("a.jpeg") == ImageFormat::Jpeg);
  CHECK_FALSE(imageFormatOfPath("a.tiff"));
  CHECK_FALSE(imageFormatOfPath("dir.png/file"));
}

TEST_CASE("GIVEN bytes the codec does not read WHEN decoded THEN the error says why", "[io][image][codec]") {
  const std::string text = "this is not a jpeg";
  CHECK_THROWS_WITH(decodeImage(reinterpret_cast<const unsigned char*>(text.data()), text.size(), ImageColor::Bgr),
                    Catch::Contains("not a JPEG, PNG, BMP or PNM image"));
  auto jpeg = readBytes(kSamples + "/1.jpg");
  CHECK_THROWS_WITH(decodeImage(jpeg.data(), jpeg.size(), ImageColor::Bgr, 1000), Catch::Contains("512x384 pixels is over the cap"));
  // Damaged scan data: libjpeg warns and would decode made-up pixels; refused instead (issue 41).
  auto overwritten = jpeg;
  std::fill(overwritten.begin() + static_cast<std::ptrdiff_t>(jpeg.size() / 2),
            overwritten.begin() + static_cast<std::ptrdiff_t>(jpeg.size() / 2 + 300), 0x55);
  CHECK_THROWS_WITH(decode(overwritten, ImageColor::Bgr), Catch::Contains("corrupt JPEG data ("));
  std::vector<unsigned char> halved(jpeg.begin(), jpeg.begin() + static_cast<std::ptrdiff_t>(jpeg.size() / 2));
  halved.push_back(0xFF);
  halved.push_back(0xD9);  // an end marker after half the scan
  CHECK_THROWS_WITH(decode(halved, ImageColor::Bgr), Catch::Contains("corrupt JPEG data ("));
  // Padding between the scan and the end marker, as some cameras' MJPEG has: libjpeg warns ("extraneous
  // bytes before marker 0xd9") but every pixel is there, so it decodes as without the padding.
  auto padded = jpeg;
  padded.insert(padded.end() - 2, {0x00, 0x00, 0x00, 0x00});
  const cv::Mat unpadded = decode(jpeg, ImageColor::Bgr);
  const cv::Mat with_padding = decode(padded, ImageColor::Bgr);
  CHECK(cv::norm(unpadded, with_padding, cv::NORM_INF) == 0.0);
  jpeg[jpeg.size() / 2] ^= 0xFF;  // one flipped byte: refused or decoded, never a crash
  try {
    decode(jpeg, ImageColor::Bgr);
  } catch (const ImageCodecError&) {
  }
  auto png = encodeImage(testPicture(20, 20, CV_8UC3), ImageFormat::Png);
  png[40] ^= 0xFF;  // inside the image data chunk: a CRC error from libpng
  CHECK_THROWS_AS(decode(png, ImageColor::Bgr), ImageCodecError);
  std::vector<unsigned char> rle = encodeImage(testPicture(8, 8, CV_8UC1), ImageFormat::Bmp);
  rle[30] = 1;  // BI_RLE8
  CHECK_THROWS_WITH(decode(rle, ImageColor::Bgr), Catch::Contains("RLE compression is not supported"));
}
